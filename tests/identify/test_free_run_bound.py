"""A plant too stiff to free-run is refused before the work starts, and ``diagnose`` answers without its figure.

Session 14: fitted effects gone sharp (a brush contact smoothed over 20 mA beside a 0.24 ohm winding, a Stribeck
band of 178 N m) asked the free run for 31,000-61,000 RK4 steps a sample: 17-127 s for one log. Both sources are
fixed (``test_brush_smoothing.py``, ``test_stribeck_bands.py``); this is the bound for the next such plant.
"""

from __future__ import annotations

import numpy as np
import pytest

import ocp.identify.predict as predict
from ocp.errors import SolverError
from ocp.identify import diagnose
from ocp.identify.estimate import free_run_errors
from ocp.identify.predict import MAX_STEPS_PER_SAMPLE, free_run, noise_levels
from ocp.model.effects import Stribeck
from ocp.model.params import load_params
from ocp.model.plant import DCMotorPlant
from tests.synthetic_rig import RigSpec, generate


def test_a_sharp_friction_is_refused_and_a_plausible_one_runs() -> None:
    """9194's fitted Stribeck level (178 N m over a 0.5 rad/s sign smoothing: a slope of ~360 N m s at standstill,
    where the simulator's step rule looks) against the paper rig's 2.7e-5 kg m^2; then a plausible 5 mN m."""
    p = load_params("paper-rig")
    log = generate(p, RigSpec(seconds=1.0, seed=1))
    with pytest.raises(SolverError) as err:
        free_run(DCMotorPlant(p, (Stribeck(tau_s=178.0, omega_s=4.5),)), log)
    assert err.value.field == "plant" and str(MAX_STEPS_PER_SAMPLE) in err.value.reason
    fr = free_run(DCMotorPlant(p, (Stribeck(tau_s=0.005, omega_s=20.0),)), log)
    assert np.all(np.isfinite(fr.omega))


def test_diagnose_answers_when_an_adopted_plant_cannot_be_free_run(monkeypatch: pytest.MonkeyPatch) -> None:
    """The bound set between the nominal plant's steps a sample (4 here) and the Coulomb candidate's (5; 7 until
    session 24's realignment moved its calibrated constants): the verdict stands, the adopted entry has no held-out
    figure."""
    p = load_params("paper-rig")
    log = generate(p, RigSpec(effects={"coulomb_friction": {"tau_c": 0.004}}, seconds=3.0, seed=3))
    monkeypatch.setattr(predict, "MAX_STEPS_PER_SAMPLE", 4)
    res = diagnose(DCMotorPlant(p), log)
    assert res.verdict == ["coulomb_friction"]
    adopted = [e for r in res.rounds for e in r.entries if e.significant]
    assert [e.name for e in adopted] == ["coulomb_friction"] and adopted[0].heldout_rms == {}


def test_a_fit_trying_a_sharp_plant_sees_a_huge_error_not_an_exception() -> None:
    """``free_run_fit``'s residual for a trial plant too stiff to free-run: 1e6 on every row it would have compared
    (the same length as a plausible plant's), so the least-squares step backs off instead of aborting the fit."""
    p = load_params("paper-rig")
    log = generate(p, RigSpec(seconds=1.0, seed=1))
    rows = np.arange(log.n) % 3 == 0
    noise = noise_levels(log)
    good = free_run_errors(DCMotorPlant(p, (Stribeck(tau_s=0.005, omega_s=20.0),)), log, rows, noise, 0.5)
    sharp = free_run_errors(DCMotorPlant(p, (Stribeck(tau_s=178.0, omega_s=4.5),)), log, rows, noise, 0.5)
    assert sharp.shape == good.shape and np.all(sharp == 1e6) and np.all(np.abs(good) < 1e6)
