import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.interpolate import CubicSpline

from ocp.model.plant import speed_from_thrust
from ocp.reference.analytic import LocalReversal, SinProfile, reference, time_grid
from tests.motor_ode import dc_motor_ode

PROFILES = [SinProfile(0.5, 2.0, q, 0.3) for q in range(4)] + [
    LocalReversal.between(-0.4, 0.5, 1.0, p, 0.8) for p in (1, 3, 5, 7)
]


@pytest.mark.parametrize("prof", PROFILES, ids=lambda p: type(p).__name__ + str(p.p))
def test_closed_form_derivatives_match_finite_differences(prof, rig):
    """omega, omega', omega'', current and voltage vs central differences, away from crossings."""
    t = np.linspace(0.05, 1.95, 400)
    h = 1e-5
    ref = reference(prof, rig, t)
    lo, mid, hi = (reference(prof, rig, t + d) for d in (-h, 0.0, h))
    near = np.zeros(t.size, bool)
    for ts in ref.crossing_times:
        near |= np.abs(t - ts) < 0.02
    away = ~near
    fd_w = (hi.omega - lo.omega) / (2 * h)
    fd_dw = (hi.omega_dot - lo.omega_dot) / (2 * h)
    np.testing.assert_allclose(mid.omega[away], speed_from_thrust(mid.thrust[away], rig.c_f), rtol=1e-12)
    np.testing.assert_allclose(fd_w[away], ref.omega_dot[away], rtol=1e-5, atol=1e-6 * np.max(np.abs(fd_w)))
    np.testing.assert_allclose(fd_dw[away], ref.omega_ddot[away], rtol=1e-4, atol=1e-5 * np.max(np.abs(fd_dw)))
    # the DC-motor equations hold along the reference (eqs. dc_mechanical / dc_electrical)
    fd_i = (hi.current - lo.current) / (2 * h)
    w, i, v = ref.omega[away], ref.current[away], ref.voltage[away]
    mech = rig.J * ref.omega_dot[away] - (rig.k_t * i - rig.B * w - rig.c_tau * w * np.abs(w))
    elec = rig.L * fd_i[away] - (v - rig.R * i - rig.k_e * w)
    assert np.max(np.abs(mech)) < 1e-12
    assert np.max(np.abs(elec)) < 1e-5 * np.max(np.abs(v))


@pytest.mark.parametrize("q", range(4))
def test_theta_closed_form_matches_quadrature(q, rig):
    prof = SinProfile(0.5, 1.3, q, 0.7)
    t = np.linspace(0.0, 3.0, 31)
    theta = prof.theta(t, rig.c_f)

    def w(tt):
        f = prof.thrust(np.array([tt]))[0][0]
        return math.copysign(math.sqrt(abs(f) / rig.c_f), f)

    brk = [c.t_s for c in prof.crossings(0.0, 3.0)]
    for k in (7, 19, 30):
        pts = [b for b in brk if b < t[k]]
        assert theta[k] == pytest.approx(quad(w, 0.0, t[k], points=pts or None, limit=200)[0], rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("q", [0, 1])
def test_low_orders_report_unbounded_never_nan(q, rig):
    t = time_grid(2.0, 1000)  # samples hit the crossings at t = 0, 1, 2
    ref = reference(SinProfile(0.5, 2.0, q), rig, t)
    for c in ("current", "voltage", "omega", "omega_dot", "omega_ddot", "thrust", "theta"):
        assert not np.isnan(getattr(ref, c)).any(), c
    assert ref.unbounded["voltage"] and np.isinf(ref.voltage[[0, 1000, 2000]]).all()
    if q == 0:
        assert ref.unbounded["current"] and np.isinf(ref.current[[0, 1000, 2000]]).all()
    else:
        assert not ref.unbounded["current"] and ref.current[1000] == 0.0
        assert np.isfinite(ref.current).all()
    # values approach the limit: |current| grows without bound towards the crossing for q = 0
    if q == 0:
        s = np.array([1e-6, 1e-4, 1e-2])
        near = reference(SinProfile(0.5, 2.0, 0), rig, 1.0 + s)
        assert np.all(np.diff(np.abs(near.current)) < 0)  # grows as s -> 0


@pytest.mark.parametrize("q", [2, 3])
def test_bounded_orders_are_finite_with_zero_limits(q, rig):
    ref = reference(SinProfile(0.5, 2.0, q), rig, time_grid(2.0, 1000))
    assert not any(ref.unbounded[c] for c in ("current", "voltage"))
    assert np.isfinite(ref.voltage).all()
    assert ref.current[1000] == 0.0 and ref.voltage[1000] == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("q", [2, 3])
def test_open_loop_simulation_reproduces_analytic_thrust(q, rig):
    """Oracle: integrate the motor (its NumPy ODE, independent of the plant's CasADi code) under the closed-form
    V_d; it must reproduce the thrust, the current and the angle. V_d is evaluated once, vectorised, on a 25 us
    grid and interpolated by a cubic spline (its error on the current is ~1e-7 A at q = 2, 70x under the
    tolerance below; a per-step call of ``reference`` made this test 5x slower)."""
    prof = SinProfile(0.5, 1.0, q)
    t = time_grid(2.0, 500)
    ref = reference(prof, rig, t)
    fine = np.linspace(t[0], t[-1], 80001)
    v = CubicSpline(fine, reference(prof, rig, fine).voltage)
    rhs, jac = dc_motor_ode(rig)

    def f(tt: float, z: np.ndarray) -> list[float]:
        return [*rhs(tt, z[:2], float(v(tt))), z[0]]  # (w, i) and the angle theta' = w

    def f_jac(tt: float, z: np.ndarray) -> list[list[float]]:
        a = jac(tt, z[:2], 0.0)
        return [[*a[0], 0.0], [*a[1], 0.0], [1.0, 0.0, 0.0]]

    sim = solve_ivp(f, (t[0], t[-1]), [ref.omega[0], ref.current[0], ref.theta[0]], method="Radau", jac=f_jac,
                    t_eval=t, rtol=1e-10, atol=1e-10)
    assert sim.success
    w, cur, theta = sim.y
    # stated tolerance: 1e-5 of the amplitude in thrust, 1e-5 A in current
    assert np.max(np.abs(rig.c_f * w * np.abs(w) - ref.thrust)) < 1e-5 * 0.5
    assert np.max(np.abs(cur - ref.current)) < 1e-5
    np.testing.assert_allclose(theta, ref.theta, atol=1e-3)


def test_local_reversal_is_exact_monomial_near_crossing(rig):
    lr = LocalReversal.between(-0.3, 0.5, 1.0, 5, 0.8)
    t = 1.0 + np.linspace(-0.1, 0.1, 11)
    f, _, _ = lr.thrust(t)
    np.testing.assert_allclose(f, lr.alpha * (t - 1.0) ** 5, rtol=1e-12, atol=1e-15)
    far = lr.thrust(np.array([0.0, 2.0]))[0]
    np.testing.assert_allclose(far, [-0.3, 0.5])


def test_local_reversal_rejects_inconsistent_signs():
    from ocp.errors import MissionError

    with pytest.raises(MissionError, match="before"):
        LocalReversal.between(0.4, 0.5, 1.0, 3, 0.8)


@pytest.mark.parametrize("q", [0, 1, 2, 3])
def test_sin_reversal_is_the_sine_power_between_its_peaks(q, rig):
    from ocp.reference.analytic import PiecewiseProfile, SinReversal

    t = np.linspace(0.5, 1.5, 1001)  # peak, crossing at t = 1 (a sample), opposite peak
    piece = reference(PiecewiseProfile((SinReversal(1.0, q, 0.4, -0.4, 0.5, 0.5),), (0.0, 2.0)), rig, t)
    exact = reference(SinProfile(0.4, 2.0, q), rig, t)
    finite = np.isfinite(exact.voltage)
    np.testing.assert_allclose(piece.thrust, exact.thrust, atol=1e-12)
    np.testing.assert_allclose(piece.voltage[finite], exact.voltage[finite], rtol=1e-9, atol=1e-9)
    assert piece.unbounded == exact.unbounded
    np.testing.assert_array_equal(np.isinf(piece.voltage), np.isinf(exact.voltage))
    # outside the window the levels hold, with zero slope at the joins
    f, df, _ = SinReversal(1.0, q, 0.4, -0.3, 0.5, 0.2).thrust(np.array([0.2, 0.5, 1.2, 1.9]))
    np.testing.assert_allclose(f, [0.4, 0.4, -0.3, -0.3], atol=1e-15)
    np.testing.assert_allclose(df, 0.0, atol=1e-9)
