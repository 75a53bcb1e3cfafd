"""The proving ground's off-catalogue shapes (``make_case(seed, shapes=True)``, ``bench/modelcheck.py --shapes``).

The identifier's catalogue writes Stribeck friction as a Gaussian decay and a ripple as a pure sine; a rig nobody
here built may do neither. The shaped draws change only those two effects, from a stream of their own, so the
reported proving ground (``shapes=False``) keeps its logs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.proving_ground import make_case
from tests.proving_ground.cases import draw_shape
from tests.proving_ground.physics import Truth, load_torque

RIG = {"J": 1e-4, "B": 0.0, "c_tau": 0.0, "c_f": 1e-5, "k": 0.02, "R": 0.8, "L": 1e-3, "v_max": 12.0}


def test_a_draw_without_friction_or_ripple_is_the_same_log_shaped() -> None:
    plain, shaped = make_case(1002), make_case(1002, shapes=True)
    assert not {"stribeck", "cogging"} & set(plain.truth.effects)  # (the class: nothing to reshape)
    for key, col in plain.columns.items():
        np.testing.assert_array_equal(shaped.columns[key], col)


@pytest.mark.parametrize("delta", [0.5, 1.0, 2.0])
def test_shaped_stribeck_decays_with_its_exponent(delta: float) -> None:
    """Oracle, closed form: ``tau_s exp(-|w / omega_s|^delta)`` (the sign's tanh at 0.1 % of the no-load speed, 0.6
    rad/s, is 1 to 1e-15 here)."""
    tau = load_torque(Truth(**RIG, effects={"stribeck": {"tau_s": 0.01, "omega_s": 20.0, "delta": delta}}))
    for w in (30.0, -45.0):
        assert tau(w, 0.0) == pytest.approx(math.copysign(0.01 * math.exp(-abs(w / 20.0) ** delta), w), rel=1e-12)


def test_shaped_ripple_carries_its_harmonics() -> None:
    """Oracle, a discrete Fourier transform over one revolution at a fixed speed: the ripple's count, and twice and
    three times it, at the drawn amplitudes; nothing else."""
    rip = {"amplitude": 0.004, "periods": 7.0, "phase": 0.3, "h2": 0.4, "phase2": 1.1, "h3": 0.2, "phase3": 2.0}
    tau = load_torque(Truth(**RIG, effects={"cogging": rip}))
    theta = np.linspace(0.0, 2 * math.pi, 1024, endpoint=False)
    spectrum = np.abs(np.fft.rfft([tau(0.0, th) for th in theta])) * 2 / theta.size
    assert spectrum[[7, 14, 21]] == pytest.approx([0.004, 0.0016, 0.0008], rel=1e-9)
    spectrum[[7, 14, 21]] = 0.0
    assert np.max(spectrum) < 1e-12


def test_a_shaped_draw_reshapes_its_stribeck_friction() -> None:
    plain, shaped = make_case(1010), make_case(1010, shapes=True)
    assert set(plain.truth.effects) == {"stribeck"} and "delta" not in plain.truth.effects["stribeck"]
    assert 0.5 <= shaped.truth.effects["stribeck"]["delta"] <= 2.0
    assert not np.array_equal(plain.columns["current"], shaped.columns["current"])


def test_shapes_are_drawn_over_their_ranges() -> None:
    rng = np.random.default_rng(5)
    strib = [draw_shape("stribeck", {"tau_s": 1.0, "omega_s": 2.0}, rng)["delta"] for _ in range(200)]
    rip = [draw_shape("cogging", {"amplitude": 1.0, "periods": 5.0, "phase": 0.0}, rng) for _ in range(200)]
    assert 0.5 <= min(strib) < 0.6 and 1.9 < max(strib) <= 2.0
    assert 0.1 <= min(r["h2"] for r in rip) and max(r["h2"] for r in rip) <= 0.5
    assert 0.0 <= min(r["h3"] for r in rip) and max(r["h3"] for r in rip) <= 0.25
    assert draw_shape("brush_drop", {"v_b": 0.3}, rng) == {"v_b": 0.3}
