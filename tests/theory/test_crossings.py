import numpy as np
import pytest

from ocp.reference.analytic import LocalReversal, SinProfile, time_grid
from ocp.theory.crossings import ORDER_TOLERANCE, classify_profile, estimate_crossings, find_zeros
from ocp.theory.reversal import CONTINUOUS, UNBOUNDED


@pytest.mark.parametrize("q", range(5))
@pytest.mark.parametrize("phase", [0.0, 0.37])
def test_sampled_sin_family_order_within_tolerance(q, phase):
    t = time_grid(3.0, 1000)
    f = SinProfile(0.5, 2.0, q, phase).thrust(t)[0]
    est = estimate_crossings(t, f)
    exact = SinProfile(0.5, 2.0, q, phase).crossings(t[1], t[-2])
    assert len(est) == len(exact)
    for e, x in zip(est, exact, strict=True):
        assert abs(e.t_s - x.t_s) < 1e-3
        assert abs(e.exponent - (2 * q + 1)) <= ORDER_TOLERANCE
        assert e.p == 2 * q + 1 and e.sign_change


@pytest.mark.parametrize("p", [1, 2, 3, 4, 6])
def test_local_reversal_orders_and_touches(p):
    t = time_grid(2.0, 1000)
    before = -0.5 if p % 2 else 0.5
    f = LocalReversal.between(before, 0.5, 1.0, p, 0.8).thrust(t)[0]
    (e,) = estimate_crossings(t, f)
    assert e.p == p and e.sign_change == bool(p % 2)


def test_speed_space_reversal_has_exponent_two_and_changes_sign():
    t = time_grid(2.0, 1000)
    s = t - 1.0003
    (e,) = estimate_crossings(t, 0.2 * s * np.abs(s))
    assert abs(e.exponent - 2.0) < 0.05 and e.sign_change


def test_classify_profile_theorem1():
    t = time_grid(2.0, 1000)
    lin = classify_profile(t, SinProfile(0.5, 2.0, 0, 0.2).thrust(t)[0], c_f=1.4e-4)
    assert lin.current == UNBOUNDED and not lin.reproducible_bounded
    quint = classify_profile(t, SinProfile(0.5, 2.0, 2, 0.2).thrust(t)[0], c_f=1.4e-4)
    assert quint.voltage == CONTINUOUS and quint.reproducible_bounded
    # a fast reversal leaves S for tight input bounds
    fast = classify_profile(t, SinProfile(0.5, 0.05, 2, 0.2).thrust(t)[0], c_f=1.4e-4, k=0.08, u_low=50.0,
                            u_high=50.0)
    assert fast.feasible_fraction < 1.0 and not fast.reproducible_bounded


def _zeros_by_scan(f, tol):
    """Sample-by-sample scan: the definition find_zeros vectorises (the oracle)."""
    out, k, n = [], 0, f.size
    while k < n:
        if abs(f[k]) <= tol:
            j = k
            while j + 1 < n and abs(f[j + 1]) <= tol:
                j += 1
            if k > 0 and j + 1 < n:
                out.append(((k + j) // 2, bool(np.sign(f[k - 1]) * np.sign(f[j + 1]) < 0)))
            k = j + 1
            continue
        if k + 1 < n and abs(f[k + 1]) > tol and f[k] * f[k + 1] < 0:
            out.append((k, True))
        k += 1
    return out


@pytest.mark.parametrize("seed", range(20))
def test_find_zeros_matches_a_sample_scan(seed):
    rng = np.random.default_rng(seed)
    f = rng.choice([-1.0, 0.0, 1.0], size=200, p=[0.4, 0.2, 0.4]) * rng.uniform(0.5, 1.0, 200)
    tol = 0.0 if seed % 2 else 0.6  # exact zeros only, or small samples counted as zero too
    found = find_zeros(np.arange(f.size, dtype=float), f, tol)
    assert found == _zeros_by_scan(f, tol)
    assert any(sign for _, sign in found) and any(not sign for _, sign in found)


def test_a_reversal_through_an_exact_zero_sample_is_found_everywhere(rig):
    """A ramp from +0.4 N to -0.4 N sampled exactly at its zero: the phase split, the fallback design and the
    comparison all see the one reversal at 0.6 s (the last two once looked for opposite-sign neighbours only)."""
    from ocp.optimize.compare import mission_reversals
    from ocp.optimize.mission import mission_from_mapping
    from ocp.optimize.problem import split_phases
    from ocp.reference.fallback import design_reversals
    from ocp.theory.reversal import ReversalRegularity

    m = mission_from_mapping({"name": "zero", "segments": [
        {"kind": "hold", "duration": 0.5, "thrust": 0.4}, {"kind": "ramp", "duration": 0.2, "to": -0.4},
        {"kind": "hold", "duration": 0.5, "thrust": -0.4}]})
    t, f = m.desired()
    assert np.count_nonzero(f == 0.0) == 1
    assert split_phases(t, f).bounds[1] == pytest.approx(0.6)
    assert [w.t_s for w in mission_reversals(t, f)] == pytest.approx([0.6])
    fb = design_reversals(rig, t, f, 1.0, 12.0, ReversalRegularity.BOUNDED)
    assert fb is not None and [p.t_s for p in fb.pieces] == pytest.approx([0.6])
