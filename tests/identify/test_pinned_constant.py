"""A named constant pinned at the edge of its box is the box's value, not the log's (issue #11: logs nobody here
generated; :func:`ocp.identify.explain.pinned`, read by :func:`ocp.identify.explain.physical`).

On the blind rig (``bench/blindrig``: its own integrator, effect formulas and loggers, written without reading the
identifier), a wrong ``R`` was named rightly in its round, then a brush drop won the next one by taking ``R`` to the
-80 % edge of the box a named constant may take (:data:`ocp.identify.lsq.NAMED_BOUNDS`): a saturating drop plus a
fifth of the resistance, fitted against what the sensors' lags leave in the armature equation. The held-out free run
of that model missed the log by several times the one before the drop.

Where a later item takes a named constant beyond the prior's factor two without pinning it (to -75 %), it
compensates it all the same (:func:`ocp.identify.select._sound`).

Oracles: the blind rig's fresh seeds 564 and 473 (their truth files: ``R`` alone, the nominal 35.8 % and 27.4 % above
the rig's; a 1 kHz ramp through zero, 1 kHz PI tracking) and 165 (a gap dead band of 1.25 V beside ``R``, the nominal
36.3 % above the rig's, a 1.4 kHz ramp), regenerated here; and, for the rule itself, a fit moved onto and just inside
the box edge.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from ocp.identify.explain import physical, pinned
from ocp.identify.lsq import NAMED_BOUNDS
from tests.identify.diagnosed import blind, diagnosed


@pytest.mark.parametrize("seed", [564, 473])
def test_a_drop_that_takes_r_to_its_box_or_beyond_a_factor_two_is_not_named(seed: int, tmp_path: Path) -> None:
    d, truth = blind(seed, tmp_path)
    drawn = truth["meta"]["calibration_rel_errors"]["R"]  # nominal / rig - 1
    assert d.verdict == ["param:R"], d.verdict
    assert d.calibration["R"]["relative"] == pytest.approx(1.0 / (1.0 + drawn) - 1.0, abs=0.02)
    drop = next(e for r in d.rounds[1:] for e in r.entries if e.name == "brush_drop")
    assert not drop.significant


def test_a_dead_band_beside_r_is_named_without_the_drop_that_compensated_r(tmp_path: Path) -> None:
    d, truth = blind(165, tmp_path)
    assert sorted(d.verdict) == ["param:R", "voltage_deadband"], d.verdict
    assert d.calibration["R"]["relative"] == pytest.approx(
        1.0 / (1.0 + truth["meta"]["calibration_rel_errors"]["R"]) - 1.0, abs=0.02)
    band = next(e for r in d.rounds for e in r.entries if e.name == "voltage_deadband" and e.significant)
    assert band.parameters["v_db"] == pytest.approx(truth["rig"]["deadband"], rel=0.1)


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
