"""The proving ground's brush contact: a dry (set-valued) drop, stepped exactly at any sub-step / (L/R).

Guards issue #11: the smooth ``v_b tanh(i/i_eps)`` drop, frozen over a sub-step, made the current flip sign
every sub-step inside the contact band once the sub-step exceeded ~5 % of L/R (the rig logs showed a current
where the physical one is zero). Rotor held at a constant speed (huge J, no load) so that
``u = V - k_e w`` [V] is constant and the armature has a closed-form solution.
"""

from __future__ import annotations

import math

import pytest

from tests.proving_ground.physics import Rig, Truth

R, L, K, W = 0.8, 1.6e-3, 0.02, 100.0  # ohm, H, V s/rad, rad/s (k_e w = 2 V)
V_B = 0.6  # brush drop [V]
RATIOS = (0.05, 1.0, 3.0)  # sub-step / (L/R)


def _held_rig(i0: float) -> Rig:
    """A rig with brushes whose rotor keeps ``W`` [rad/s] (J = 1e30 kg m^2, no torque), current ``i0`` [A]."""
    t = Truth(J=1e30, B=0.0, c_tau=0.0, c_f=0.0, k=K, R=R, L=L, v_max=24.0, effects={"brush_drop": {"v_b": V_B}})
    rig = Rig(t)
    rig.w, rig.i = W, i0
    return rig


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("u", [0.0, 0.4, -0.59])
def test_inside_the_band_the_current_stays_zero(ratio: float, u: float) -> None:
    rig = _held_rig(0.0)
    for _ in range(40):
        rig.substep(K * W + u, ratio * L / R)
        assert rig.i == 0.0


@pytest.mark.parametrize("ratio", RATIOS)
def test_inside_the_band_a_current_decays_to_zero_and_stays(ratio: float) -> None:
    """From 1 A with u = 0.3 V: L di/dt = u - v_b - R i until i = 0, at t0 = (L/R) ln((1 - a)/(-a))."""
    u, h = 0.3, ratio * L / R
    a = (u - V_B) / R  # the asymptote the decay aims at [A] (< 0)
    t0 = L / R * math.log((1.0 - a) / -a)
    rig = _held_rig(1.0)
    for k in range(1, 60):
        rig.substep(K * W + u, h)
        want = a + (1.0 - a) * math.exp(-k * h * R / L) if k * h < t0 else 0.0
        assert rig.i == pytest.approx(want, abs=1e-12)
    assert rig.i == 0.0


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("u", [1.5, -2.0])
def test_outside_the_band_the_drop_is_constant(ratio: float, u: float) -> None:
    """From i = 0: i(t) = (u - v_b sign(u))/R (1 - exp(-t R/L)), the exact exponential with a constant drop."""
    h = ratio * L / R
    i_ss = (u - math.copysign(V_B, u)) / R
    rig = _held_rig(0.0)
    for k in range(1, 30):
        rig.substep(K * W + u, h)
        assert rig.i == pytest.approx(i_ss * (1.0 - math.exp(-k * h * R / L)), rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("ratio", RATIOS)
def test_a_current_reversing_within_a_step_is_split_at_zero(ratio: float) -> None:
    """From 1 A with u = -2 V: down to 0 with drop +v_b, then negative with drop -v_b (in one step or across)."""
    u, h = -2.0, ratio * L / R
    a, b = (u - V_B) / R, (u + V_B) / R
    t0 = L / R * math.log((1.0 - a) / -a)
    rig = _held_rig(1.0)
    for k in range(1, 30):
        rig.substep(K * W + u, h)
        t = k * h
        want = a + (1.0 - a) * math.exp(-t * R / L) if t < t0 else b * (1.0 - math.exp(-(t - t0) * R / L))
        assert rig.i == pytest.approx(want, rel=1e-9, abs=1e-12)


def test_the_mechanics_see_the_exact_charge_of_a_split_step() -> None:
    """One sub-step of 3 L/R from 1 A with u = -2 V (a reversal inside it): the rotor, with no load torque, gains
    k_t/J times the exact charge [A s] of the two exponential pieces (RK4 is exact for a constant torque)."""
    u, h, tau = -2.0, 3.0 * L / R, L / R
    a, b = (u - V_B) / R, (u + V_B) / R
    t0 = tau * math.log((1.0 - a) / -a)
    charge = a * t0 + (1.0 - a) * tau * (1.0 - math.exp(-t0 / tau)) \
        + b * ((h - t0) - tau * (1.0 - math.exp(-(h - t0) / tau)))
    rig = _held_rig(1.0)
    rig.t.J = 1e-6  # kg m^2: a visible speed change, the current step still sees the speed at the step start
    rig.substep(K * W + u, h)
    assert (rig.w - W) * rig.t.J / K == pytest.approx(charge, rel=1e-9)
