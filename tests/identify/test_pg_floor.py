"""``bench/pg_floor.py`` (the torque equation's floor against a load item's footprint, docs/model-check-rules.md). On
proving-ground rigs drawn with Coulomb friction the footprint is the rotor's low-pass of ``tau_c tanh(w / eps)``, a
filter with a non-negative impulse response of unit area, so it never exceeds ``tau_c``; it is the rig's, not the
sensors' (the same on the log recorded again without noise), and sensor noise only raises the floor. A ripple's row
mean meets the windows' closed forms; ``--records`` takes the required misses. The script had drifted from the
proving ground's ``load_torque`` (a scalar function of the rig since) and crashed on every item."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from bench import pg_floor
from bench.modelcheck import noise_free
from ocp.identify.columns import Signals
from tests.proving_ground import make_case


@pytest.mark.parametrize("seed", [119, 121])  # Coulomb friction alone: 5 kHz encoder, 200 Hz encoder
def test_a_friction_footprint_is_bounded_by_its_level_and_not_the_noise(seed: int) -> None:
    case = make_case(seed, "one")
    tau_c = case.truth.effects["coulomb_friction"]["tau_c"]
    floor, foot = pg_floor.floor_and_footprint(case, "coulomb_friction")
    quiet_floor, quiet_foot = pg_floor.floor_and_footprint(noise_free(case), "coulomb_friction")
    assert 0.0 < foot <= tau_c
    assert quiet_foot == pytest.approx(foot, rel=0.05)
    assert 0.0 < quiet_floor <= floor


def test_the_script_prints_one_line_per_item(capsys: pytest.CaptureFixture[str]) -> None:
    assert pg_floor.main(["--items", "17:coulomb_friction", "17:thrust_asymmetry"]) == 0  # (seed 17's
    out = capsys.readouterr().out.splitlines()  # own draw: Coulomb friction alone, 200 Hz, a tachometer)
    row = re.match(r"\s*17 coulomb_friction .* floor\s+(\S+) N m footprint\s+(\S+) N m\s+ratio\s+(\S+)", out[0])
    assert row is not None
    floor, foot, ratio = (float(x) for x in row.groups())
    assert foot > 0.0 and ratio == pytest.approx(foot / floor, rel=0.01)
    assert out[1].startswith("17:thrust_asymmetry: not a load-torque item")
    assert out[-1] == f"footprint under the floor: {int(foot < floor)} of 2"


def test_records_give_the_required_misses_of_a_label(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--records``: a record that missed seed 17's Coulomb friction (its own draw, which the audit finds visible
    beyond calibration) is measured; one whose verdict named it is not, nor is a label the rig was not drawn with."""
    rec = {"seed": 17, "kind": "one", "expected": ["coulomb_friction"], "verdict": []}
    path = tmp_path / "records.json"
    path.write_text(json.dumps([rec, {**rec, "seed": 18, "verdict": ["coulomb_friction"]},
                                {**rec, "seed": 19, "expected": ["stribeck"]}]), encoding="utf-8")
    assert pg_floor.main(["--records", str(path), "--label", "coulomb_friction"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and re.match(r"\s*17 coulomb_friction .* ratio", out[0])
    assert out[1].startswith("footprint under the floor: ") and out[1].endswith(" of 1")


@pytest.mark.parametrize("x", [0.3, 1.0, math.pi])  # half the phase a row of the ripple spans (pi: none is left)
@pytest.mark.parametrize("triangle", [True, False])
def test_a_ripple_is_averaged_along_the_rows_path(x: float, triangle: bool) -> None:
    """At a constant speed ``w`` a ripple ``sin(n theta)`` averages to ``sin(n theta_k)`` times the window's transfer
    at ``n w``: ``sinc(x)^2`` under the raw rows' triangle over k-1 -> k+1, ``x = n w dt / 2``; over a row k -> k+1
    the box's exact mean ``(cos(n theta_k) - cos(n theta_k + 2 x)) / (2 x)`` (closed forms, not the script's sums)."""
    n, dt, m = 7.0, 1e-3, 50
    w = 2.0 * x / (n * dt)
    theta = np.linspace(0.0, 3.0, m)
    ones = np.full(m, w)
    s = Signals(ones, ones, ones, ones, ones, ones, ones, ones, theta, np.arange(m) * dt, dt, triangle=triangle)
    got = pg_floor.row_mean(lambda _w, a: math.sin(n * a), s, theta)
    want = np.sin(n * theta) * (math.sin(x) / x) ** 2 if triangle else \
        (np.cos(n * theta) - np.cos(n * theta + 2.0 * x)) / (2.0 * x)
    assert np.max(np.abs(got - want)) < 0.01
