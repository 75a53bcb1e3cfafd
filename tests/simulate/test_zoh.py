"""The one zero-order-hold simulator (ocp.simulate.zoh): its stability rule against the plant's closed-form
eigenvalues, its answers against scipy's Radau, and the compiled step against the CasADi virtual machine."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.errors import MissionError
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate import compiled, zoh
from ocp.simulate.open_loop import simulate_zoh


def test_the_step_follows_the_closed_form_fastest_eigenvalue(rig: MotorParams) -> None:
    """At rest the DC motor is linear: A = [[-B/J, k_t/J], [-k_e/L, -R/L]]; the step is SUBSTEPS * 0.32 / max|eig|."""
    for inductance in (2e-3, 2e-5):
        p = rig.model_copy(update={"L": inductance})
        a = np.array([[-p.B / p.J, p.k_t / p.J], [-p.k_e / p.L, -p.R / p.L]])
        lam = float(np.max(np.abs(np.linalg.eigvals(a))))
        step = zoh.step_limit(DCMotorPlant(p), np.zeros(2), 0.0, max_step=np.inf)
        assert step == pytest.approx(zoh.SUBSTEPS * zoh.RK4_STIFFNESS / lam, rel=1e-12)
    assert zoh.step_limit(DCMotorPlant(rig), np.zeros(2), 0.0) <= zoh.SIM_STEP


def test_simulate_zoh_matches_radau_on_a_stiff_winding(rig: MotorParams) -> None:
    """Random held voltages reversing a motor with a 20 uH winding (L/R = 4 us): the simulator agrees with Radau
    IIA restarted at every sample (a fixed 0.1 ms RK4 sub-step would diverge)."""
    plant = DCMotorPlant(rig.model_copy(update={"L": 2e-5}))
    p = plant.params

    def jac(z: np.ndarray) -> np.ndarray:  # analytic Jacobian of eqs. dc_mechanical, dc_electrical
        return np.array([[(-p.B - 2.0 * p.c_tau * abs(z[0])) / p.J, p.k_t / p.J], [-p.k_e / p.L, -p.R / p.L]])

    t = np.linspace(0.0, 0.06, 7)
    u = np.random.default_rng(3).uniform(-12.0, 12.0, t.size)
    u[:3] = -12.0  # reverse first
    sim = simulate_zoh(plant, t, u, (15.0, 0.0))
    x = np.array([15.0, 0.0])
    ref = [x]
    for k in range(t.size - 1):
        sol = solve_ivp(lambda _t, z, v=u[k]: plant.rhs(list(z), v), (t[k], t[k + 1]), x, method="Radau",
                        rtol=1e-11, atol=1e-13, jac=lambda _t, z: jac(z))
        x = sol.y[:, -1]
        ref.append(x)
    ref_x = np.array(ref).T
    assert np.min(ref_x[0]) < 0 < np.max(ref_x[0])
    np.testing.assert_allclose(sim.x[0], ref_x[0], rtol=0, atol=1e-6 * np.max(np.abs(ref_x[0])))
    np.testing.assert_allclose(sim.x[1], ref_x[1], rtol=0, atol=1e-4 * np.max(np.abs(ref_x[1])))


def test_a_plant_too_stiff_for_the_step_budget_is_a_clear_error(rig: MotorParams) -> None:
    plant = DCMotorPlant(rig.model_copy(update={"L": 1e-8}))
    with pytest.raises(MissionError) as err:
        zoh.simulate_held(plant, np.array([0.0, 2.0]), np.array([1.0]), np.zeros(2), np.linspace(0.0, 2.0, 3))
    assert err.value.field == "params" and "too stiff" in err.value.reason


def test_bad_initial_state_names_the_field(rig: MotorParams) -> None:
    t = np.linspace(0.0, 0.01, 11)
    with pytest.raises(MissionError) as err:
        simulate_zoh(DCMotorPlant(rig), t, np.ones_like(t), (0.0, float("nan")))
    assert err.value.field == "x0"


@pytest.mark.skipif(compiled.compiler() is None, reason="no C compiler on the PATH")
def test_the_compiled_step_gives_the_virtual_machines_numbers(rig: MotorParams, tmp_path: Path,
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Same expression graph in C (no fast-math, no FMA contraction): equal to 1e-12 relative (bit-identical on
    x86-64 with gcc), over 10k steps of a reversal with varying step lengths; the library lands in the cache
    directory and a second object for the same step loads it from disk."""
    monkeypatch.setenv("THRUSTSHAPE_CACHE_DIR", str(tmp_path))
    plant = DCMotorPlant(rig.model_copy(update={"B": 1.234e-6}))  # a plant no other test compiles
    rng = np.random.default_rng(7)
    steps = 10_000
    u = rng.uniform(-12.0, 12.0, steps)
    dt = rng.uniform(0.5e-4, 2.5e-4, steps)
    x0 = np.array([30.0, -0.2])
    vm = zoh.accumulator(plant, steps, compile_step=False)(x0, u, dt)
    driver = compiled.CompiledStep(zoh.step_function(plant)).get(wait=True)
    assert driver is not None
    assert list(tmp_path.glob("sim/zoh_step_*.so"))
    fast = driver(x0, u, dt)
    assert fast.shape == vm.shape == (2, steps)
    assert np.min(vm[0]) < 0 < np.max(vm[0])
    np.testing.assert_allclose(fast, vm, rtol=1e-12, atol=0)


def test_compiling_can_be_turned_off(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("THRUSTSHAPE_SIM_COMPILE", "0")
    assert not compiled.enabled()


def test_union_sorted_is_numpys_union1d() -> None:
    """The merge of two increasing grids gives ``np.union1d``'s array (values and length), shared values kept once;
    any other input goes to ``np.union1d`` itself."""
    rng = np.random.default_rng(11)
    for _ in range(200):
        a = np.unique(rng.choice(rng.uniform(0.0, 2.0, 300), rng.integers(1, 300)))
        b = np.unique(np.concatenate([rng.choice(a, rng.integers(0, a.size + 1)), rng.uniform(-0.5, 2.5, 40)]))
        b = b[: rng.integers(0, b.size + 1)]
        for x, y in ((a, b), (b, a)):
            got = zoh.union_sorted(x, y)
            assert got.dtype == np.float64
            np.testing.assert_array_equal(got, np.union1d(x, y))
    unsorted = np.array([0.3, 0.1, 0.2, 0.1])
    np.testing.assert_array_equal(zoh.union_sorted(unsorted, np.array([0.15])), np.union1d(unsorted, [0.15]))


def _former_simulate_held(plant: DCMotorPlant, t_knots: np.ndarray, u_of_interval: np.ndarray, x0: np.ndarray,
                          t_out: np.ndarray, compile_step: bool) -> zoh.Response:
    """simulate_held as it was before the grid's knot and output indices were read off the coarse grid (main at
    8bc3704): a sort of both grids, and searches over the fine grid."""
    grid = np.union1d(t_knots, t_out)
    step_max = zoh.step_limit(plant, x0, float(u_of_interval[0]), zoh.SIM_STEP)
    fine = zoh.fine_grid(grid, step_max)
    k = np.clip(np.searchsorted(t_knots, fine[:-1], side="right") - 1, 0, u_of_interval.size - 1)
    u = u_of_interval[k]
    xs = zoh.accumulator(plant, fine.size - 1, compile_step)(np.asarray(x0, float), u, np.diff(fine))
    states = np.concatenate([np.asarray(x0, float)[:, None], xs], axis=1)
    idx = np.clip(np.searchsorted(fine, t_out), 0, fine.size - 1)
    return zoh.Response(at_out=states[:, idx], t=fine, x=states, u=np.append(u, u[-1]))


@pytest.mark.parametrize("compile_step", [False, True])
def test_simulate_held_gives_the_former_numbers_bit_for_bit(rig: MotorParams, compile_step: bool) -> None:
    """Held voltages on irregular knots (some shared with the 1 kHz output times, some between them, the last
    past the last output): the integration grid, the input on it, the states and the states at the output times
    equal the former implementation's to the last bit."""
    plant = DCMotorPlant(rig)
    if compile_step:
        compiled.CompiledStep(zoh.step_function(plant)).get(wait=True)
    rng = np.random.default_rng(2)
    t_out = np.linspace(0.0, 0.8, 801)
    knots = np.unique(np.concatenate([[0.0], rng.choice(t_out, 40), rng.uniform(0.0, 0.85, 60), [0.85]]))
    u = rng.uniform(-12.0, 12.0, knots.size - 1)
    x0 = np.array([40.0, 0.1])
    new = zoh.simulate_held(plant, knots, u, x0, t_out, compile_step=compile_step)
    old = _former_simulate_held(plant, knots, u, x0, t_out, compile_step)
    for name in ("at_out", "t", "x", "u"):
        np.testing.assert_array_equal(getattr(new, name), getattr(old, name))


@pytest.mark.parametrize("inductance", [2e-3, 2.53e-3, 2.6e-3, 2e-5])
def test_the_step_limit_is_the_eigenvalue_rule_exactly(rig: MotorParams, inductance: float) -> None:
    """Where the Jacobian's row-sum bound already allows SIM_STEP the eigenvalues are skipped: the step equals the
    eigenvalue rule's to the last bit, at rest and at speeds up to 3000 rad/s, on windings either side of the bound
    (the paper rig's 2 mH: 2.53e-4 s allowed by the bound, SIM_STEP 2.5e-4 s)."""
    plant = DCMotorPlant(rig.model_copy(update={"L": inductance}))
    for w in (0.0, 150.0, -800.0, 3000.0):
        for u in (0.0, 12.0):
            x0 = np.array([w, 0.3])
            lam = zoh.fastest_rate(plant, x0, u)
            expect = min(zoh.SIM_STEP, zoh.SUBSTEPS * zoh.RK4_STIFFNESS / lam)
            assert zoh.step_limit(plant, x0, u) == expect
