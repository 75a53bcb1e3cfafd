"""Dry friction is set-valued where the rotor is at rest (issue #11, session 19).

Where the rotor stands, dry friction holds whatever torque stays within its level: the torque equation's residual
there is wherever the rotor stopped, which no smooth friction column fits. On a periodic trajectory (a loop reversing
at the same angles) that residual is a function of the angle, and a ripple of some count fitted it on held-out rows
too: the ripple was named beside dry friction on rigs that had none. Beside dry friction the ripple's columns are now
left out at the rows at rest (:func:`ocp.identify.columns.at_rest`, :func:`ocp.identify.select.fit_model`).
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose, regression
from ocp.identify.columns import REST_ROWS, at_rest, held_still, signals
from ocp.identify.noise_level import white_noise
from ocp.logs import Log, log_from_arrays
from ocp.model.effects import Stribeck
from ocp.model.params import MotorParams, load_params
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case

RATE = 1000.0


def _rest_log(stand: tuple[int, int], noise: float, seed: int = 0) -> tuple[np.ndarray, MotorParams, Log]:
    """A 1 kHz log whose rotor runs a 1 Hz sine of 40 rad/s, standing still over the samples ``stand`` (from a zero
    crossing, a multiple of 500; the sine resumes after them); speed noise ``noise`` [rad/s] per sample. Returns
    the true speed (N,) [rad/s], the plant's constants and the log."""
    n = 2000 + stand[1] - stand[0]
    k = np.arange(n)
    phase = np.where(k < stand[0], k, np.where(k < stand[1], stand[0], k - (stand[1] - stand[0])))
    w = 40.0 * np.sin(2 * np.pi * phase / RATE)
    rng = np.random.default_rng(seed)
    log = log_from_arrays(k / RATE, np.zeros(n), np.zeros(n), np.zeros(n), omega=w + noise * rng.normal(size=n))
    return w, load_params("paper-rig"), log


def test_the_rows_at_rest_are_those_where_the_rotor_stands() -> None:
    """Oracle: the constructed stand-still (the low-pass's transition at its ends aside) and the running rows."""
    stand = (500, 700)
    w, p, log = _rest_log(stand, noise=0.05)
    s = signals(log, p)
    rest = at_rest(s, log, p)
    assert white_noise(log.omega) == pytest.approx(0.05, rel=0.2)
    assert rest[stand[0] + 10:stand[1] - 10].all()
    running = np.abs(w[:-1]) > 2.0  # (a sine through zero stands within the noise for a few rows only)
    assert not rest[running].any()
    assert rest.sum() < (stand[1] - stand[0]) + 20


def test_a_standstill_shorter_than_the_run_is_no_rest() -> None:
    _, p, log = _rest_log((500, 500 + REST_ROWS - 1), noise=0.05)
    rest = at_rest(signals(log, p), log, p)
    assert not rest[450:550].any()


@pytest.mark.parametrize("seed", [11195, 9218])
def test_dry_friction_alone_is_named_without_a_ripple(seed: int) -> None:
    """Proving-ground draws (not the reported seeds) of dry friction alone, Coulomb and Stribeck, on which a ripple
    was named beside it before (session 18's code)."""
    case = make_case(seed)
    assert "cogging" not in case.expected and case.expected & {"coulomb_friction", "stribeck"}
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert set(res.verdict) == case.expected


def _balanced_current(w: np.ndarray, p: MotorParams) -> np.ndarray:
    """The current [A] (N,) that moves the rotor along ``w`` (N,) [rad/s] at 1 kHz with nothing else acting:
    eq. dc_mechanical ``k_t i = J w' + B w + c_tau w|w|``, ``w'`` by central differences."""
    return (p.J * np.gradient(w, 1.0 / RATE) + p.B * w + p.c_tau * w * np.abs(w)) / p.k_t


@pytest.mark.parametrize("hold", [0.0, 0.02, -0.02])
def test_a_rotor_stands_held_only_against_a_torque(hold: float) -> None:
    """Oracle by construction: the rotor stands over 200 samples while the current is ``hold`` [A] (the paper rig's
    k_t 0.0573 N m/A: 1.1 mN m, which would move the free rotor by ~8 rad/s over the stand) and follows the free
    torque balance elsewhere. Held where the current pushes and the rotor stays; not held where nothing pushes."""
    stand = (500, 700)
    w, p, log = _rest_log(stand, noise=0.05)
    cur = _balanced_current(w, p)
    cur[stand[0]:stand[1]] = hold
    log = log_from_arrays(log.t, log.voltage, cur, log.thrust, omega=log.omega)
    s = signals(log, p)
    held = held_still(s, log, p, at_rest(s, log, p))
    assert held.sum() <= at_rest(s, log, p).sum()
    if hold == 0.0:
        assert not held.any()
    else:
        assert held[stand[0] + 10:stand[1] - 10].all()
        assert not held[:stand[0] - 20].any() and not held[stand[1] + 20:].any()


def test_a_slow_free_crossing_is_at_rest_but_not_held() -> None:
    """A 0.05 Hz, 4 rad/s sine stays within the speed noise for tens of rows at each zero crossing (at rest, by the
    noise), while its current is the free torque balance's: the speed changes as the torque says, nothing holds it."""
    k = np.arange(40_000)
    w = 4.0 * np.sin(2 * np.pi * 0.05 * k / RATE)
    p = load_params("paper-rig")
    rng = np.random.default_rng(1)
    log = log_from_arrays(k / RATE, np.zeros(k.size), _balanced_current(w, p), np.zeros(k.size),
                          omega=w + 0.05 * rng.normal(size=k.size))
    s = signals(log, p)
    assert at_rest(s, log, p).sum() > 20
    assert not held_still(s, log, p, at_rest(s, log, p)).any()


def test_stribeck_friction_that_holds_the_rotor_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground draw 13077 (a validation seed, not a reported one): Stribeck friction alone, 5.3 mN m at
    16 rad/s, a 100 Hz tachometer, steps that stall the rotor against the friction. With the rows where it is held
    in the torque equation (before session 23) the Stribeck column at zero speed fitted the holding torque badly,
    the held-out error rose by 40 % and nothing was named; with them left out it is named near its truth."""
    case = make_case(13077)
    assert case.expected == {"stribeck"}
    log = case_log(case)
    p = MotorParams(**case.nominal)
    s = signals(log, p)
    assert held_still(s, log, p, at_rest(s, log, p)).sum() >= 10
    res = diagnose(DCMotorPlant(p), log)
    assert res.verdict == ["stribeck"]
    (fitted,) = res.plant.effects
    assert isinstance(fitted, Stribeck)
    assert fitted.tau_s == pytest.approx(case.truth.effects["stribeck"]["tau_s"], rel=0.5)
    monkeypatch.setattr(regression, "held_still", lambda s, log, p, rest: np.zeros_like(rest))
    assert "stribeck" not in diagnose(DCMotorPlant(p), log).verdict


def test_cut_raw_rows_are_tapered_so_no_ripple_fits_the_cut(monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground draw 13012 (a validation seed): Coulomb friction and a force offset, steps logged at 5 kHz by a
    1024-count encoder, the rotor held between steps. The torque rows are raw there (mean speeds from the angle, 7.7
    rad/s a count per row): cut off hard where the rotor is held, each cut left a count's step in the speed view,
    and a ripple fitted the steps (named beside the right two). Tapered in like the log's ends, only the two."""
    case = make_case(13012)
    assert case.expected == {"coulomb_friction", "force_offset"} and case.logger.speed == "encoder"
    log = case_log(case)
    p = MotorParams(**case.nominal)
    s = signals(log, p)
    assert held_still(s, log, p, at_rest(s, log, p)).sum() >= 100
    assert set(diagnose(DCMotorPlant(p), log).verdict) == case.expected
    # (cut off hard, as low-passed rows are)
    monkeypatch.setattr(regression, "cut_taper", lambda edge, stuck, raw, rows: regression.edge_taper(edge, rows))
    assert "cogging" in diagnose(DCMotorPlant(p), log).verdict
