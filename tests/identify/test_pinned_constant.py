"""A named constant pinned at the edge of its box is the box's value, not the log's (issue #11: logs nobody here
generated; :func:`ocp.identify.explain.pinned`, read by :func:`ocp.identify.explain.physical`).

On the blind rig (``bench/blindrig``: its own integrator, effect formulas and loggers, written without reading the
identifier), a wrong ``R`` was named rightly in its round, then a brush drop won the next one by taking ``R`` to the
-80 % edge of the box a named constant may take (:data:`ocp.identify.lsq.NAMED_BOUNDS`): a saturating drop plus a
fifth of the resistance, fitted against what the sensors' lags leave in the armature equation. The held-out free run
of that model missed the log by several times the one before the drop.

Oracles: the blind rig's fresh seed 564 (its truth file: ``R`` alone, the nominal 35.8 % above the rig's, a 1 kHz ramp
through zero), regenerated here; and, for the rule itself, a fit moved onto and just inside the box edge.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import pytest

from ocp.identify import diagnose
from ocp.identify.explain import physical, pinned
from ocp.identify.lsq import NAMED_BOUNDS
from ocp.logs import read_log
from ocp.model.effects import load_plant
from tests.identify.diagnosed import diagnosed

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from blindrig.case import generate


def test_a_drop_that_pins_r_at_its_box_is_not_named(tmp_path: Path) -> None:
    csv, params, truth = generate(564, tmp_path)
    drawn = json.loads(Path(truth).read_text())["meta"]["calibration_rel_errors"]["R"]  # nominal / rig - 1
    d = diagnose(load_plant(params), read_log(csv))
    assert d.verdict == ["param:R"], d.verdict
    assert d.calibration["R"]["relative"] == pytest.approx(1.0 / (1.0 + drawn) - 1.0, abs=0.02)
    drop = next(e for r in d.rounds[1:] for e in r.entries if e.name == "brush_drop")
    assert not drop.significant


@pytest.mark.parametrize(("edge", "inside"), [(0, 0.01), (1, -0.01)])
def test_a_named_constant_at_either_edge_is_pinned(edge: int, inside: float,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground 190 (`k` 38 % low beside a dead band, named right): its final fit is physical; with `k`'s
    coefficient moved onto an edge of the box it is pinned and unphysical, a hundredth inside it is not."""
    _, res, design, final = diagnosed(190, True, monkeypatch)
    assert "param:k" in res.verdict and pinned(design, final) is None and physical(design, final)
    (j,) = design.index("k")
    k = final.cols.index(j)
    on, near = final.x.copy(), final.x.copy()
    on[k], near[k] = NAMED_BOUNDS[edge], NAMED_BOUNDS[edge] + inside
    assert pinned(design, dataclasses.replace(final, x=on)) == "k"
    assert not physical(design, dataclasses.replace(final, x=on))
    assert pinned(design, dataclasses.replace(final, x=near)) is None
