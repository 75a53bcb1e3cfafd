"""The free run's current is read through the current sensor's lag (:func:`ocp.identify.predict.read_current`).

Before session 27 the free run compared the simulated current with the logged one as if the logger read it
unfiltered: a firmware's first-order filter (half the proving ground's loggers) made an exact plant's free run
fail in current, 19 noise units at the 90th percentile of the clean and constant-only logs of seeds 0..199. ``check``
and ``diagnose`` now fit the lag (a grid of tenths of a sample) and report it.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bench.modelcheck import case_log
from clients.cli import main
from ocp.identify import FitOptions, check, diagnose, fit
from ocp.identify.check import CheckOptions, CheckResult
from ocp.identify.diagnose import aligned, score, split
from ocp.identify.predict import CURRENT_LAGS, FreeRun, free_run, lagged_current, read_current
from ocp.identify.result import DiagnoseOptions
from ocp.logs import log_from_arrays, write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _run(current: np.ndarray, length: int) -> FreeRun:
    z = np.zeros(current.size)
    return FreeRun(np.arange(current.size), z, current, z, length)


def _firmware(current: np.ndarray, length: int, alpha: float) -> np.ndarray:
    """A firmware's filter ``acc += alpha (i - acc)`` sample by sample, restarted from each segment's first row."""
    out = current.astype(float).copy()
    for s in range(0, current.size, length):
        acc = current[s]
        for k in range(s + 1, s + length):
            acc += alpha * (current[k] - acc)
            out[k] = acc
    return out


def test_the_filter_matches_its_closed_forms() -> None:
    """Oracle: closed forms of ``y += a (x - y)``: a unit step from 0 reads ``1 - (1 - a)^k``; a ramp of slope 1
    settles ``(1 - a) / a`` (the lag) samples behind; lag 0 leaves the current as it is."""
    n, lag = 60, 0.5
    a = 1.0 / (1.0 + lag)
    step = np.r_[0.0, np.ones(n - 1)]
    np.testing.assert_allclose(lagged_current(_run(step, n), lag), 1.0 - (1.0 - a) ** np.arange(n), atol=1e-12)
    ramp = np.arange(n, dtype=float)
    assert ramp[-1] - lagged_current(_run(ramp, n), lag)[-1] == pytest.approx(lag, abs=1e-9)
    np.testing.assert_array_equal(lagged_current(_run(ramp, n), 0.0), ramp)


@pytest.mark.parametrize("lag", [0.0, 0.3, 0.7, 1.5])
def test_the_lag_of_a_firmware_filter_is_found(lag: float) -> None:
    """A current of steps and a sine in segments of 50 rows, read by the firmware's filter of that lag (written
    sample by sample, independently): the lag found is that one (a grid value), fitted on half the rows."""
    rng = np.random.default_rng(3)
    length, segs = 50, 8
    k = np.arange(length * segs)
    true = np.sin(0.21 * k) + np.repeat(rng.uniform(-1, 1, 40), k.size // 40)
    measured = _firmware(true, length, 1.0 / (1.0 + lag))
    log = log_from_arrays(k * 1e-3, np.zeros(k.size), measured, np.zeros(k.size), omega=np.zeros(k.size))
    rows = (k // length) % 2 == 0
    read = read_current(_run(true, length), log, rows)
    assert lag in CURRENT_LAGS and read.current_lag == lag
    np.testing.assert_allclose(read.current, measured, atol=1e-9)


def test_no_fitting_row_or_equilibria_leave_the_run_as_it_is() -> None:
    n = 60
    fr = _run(np.arange(float(n)), 10)
    log = log_from_arrays(np.arange(n) * 1e-3, np.zeros(n), np.zeros(n), np.zeros(n), omega=np.zeros(n))
    assert read_current(fr, log, np.zeros(n, bool)) is fr
    assert read_current(_run(np.arange(float(n)), 1), log, np.ones(n, bool)).current_lag == 0.0
    assert read_current(fr, log, np.ones(n, bool)).current_lag == CURRENT_LAGS[-1]  # (a ramp from 0 lags far)


#: fresh clean proving-ground draws (its own logger and filter) whose current filter lags 0.4 - 0.66 samples
DRAWS = (21016, 21028, 21030, 21043)


@pytest.mark.parametrize("seed", DRAWS)
def test_an_exact_plant_is_checked_near_its_noise_through_the_loggers_filter(seed: int) -> None:
    """Oracle: the proving ground's logger (``alpha``; lag ``(1 - alpha) / alpha``). The exact plant's free-run
    current error read through the lag fitted is at most half the unread one (measured: 27 -> 6.1, 22 -> 3.7,
    12 -> 1.3, 12 -> 2.6 noise units), the lag is the logger's within 0.2 samples, and the JSON reports it."""
    case = make_case(seed, "clean")
    truth_lag = (1.0 - case.logger.alpha) / case.logger.alpha
    assert truth_lag > 0.35
    plant, log = DCMotorPlant(MotorParams(**case.nominal)), case_log(case)
    res = check(plant, log)
    assert isinstance(res, CheckResult)
    _, realigned = aligned(plant, log, CheckOptions().max_logging_skew)
    unread = free_run(plant, realigned, CheckOptions().segment_s)
    np.testing.assert_array_equal(unread.idx, res.free.idx)
    assert res.free.current_lag == pytest.approx(truth_lag, abs=0.2)
    assert res.free_run_rms["current"] < 0.5 * np.sqrt(np.mean((log.current[unread.idx] - unread.current) ** 2))
    assert res.to_dict()["free_run"]["current_sensor_lag"] == res.free.current_lag


def test_diagnose_scores_held_out_rows_through_the_lag_fitted_on_the_others() -> None:
    """The same for ``diagnose``'s held-out scores (the lag fitted on the training segments): the user's exact
    plant's held-out current error is under half what it is unread, and each round reports the lag."""
    case = make_case(DRAWS[1], "clean")
    plant, log = DCMotorPlant(MotorParams(**case.nominal)), case_log(case)
    res = diagnose(plant, log)
    assert res.verdict == []
    first = res.to_dict()["rounds"][0]
    assert first["current_sensor_lag"] == pytest.approx((1.0 - case.logger.alpha) / case.logger.alpha, abs=0.2)
    opt = DiagnoseOptions()
    seg = min(opt.segment_s, log.n * log.dt / (3 * opt.holdout_every))
    test = split(log, seg, opt.holdout_every).test
    _, realigned = aligned(plant, log, opt.max_logging_skew)
    unread = score(plant, realigned, test, res.noise, seg, sensor=False)
    assert first["baseline_rms"]["current"] < 0.5 * unread.rms["current"]


def test_the_cli_says_through_which_lag_the_current_was_read(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    """``thrustshape check`` prints the lag beside the free-run errors, as the JSON has it."""
    case = make_case(DRAWS[0], "clean")
    log_path, params = tmp_path / "rig.csv", tmp_path / "motor.json"
    write_log_csv(case_log(case), log_path)
    params.write_text(json.dumps(MotorParams(**case.nominal).model_dump()), encoding="utf-8")
    assert main(["check", str(log_path), "--params", str(params), "--json"]) == 0
    lag = json.loads(capsys.readouterr().out)["free_run"]["current_sensor_lag"]
    assert lag > 0.3
    assert main(["check", str(log_path), "--params", str(params)]) == 0
    assert f"current read through the sensor's lag fitted, {lag:.1f} samples:" in capsys.readouterr().out


def test_fit_says_through_which_lags_its_before_and_after_were_read(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    """``fit``'s before/after free-run errors are read as ``check``'s are: the user's plant through the lag
    ``check`` fits (the same log, the same alignment), both lags in the JSON and on the CLI's before/after line."""
    case = make_case(DRAWS[0], "clean")
    plant, log = DCMotorPlant(MotorParams(**case.nominal)), case_log(case)
    res = fit(plant, log, ["param:R"], FitOptions(refine=False))
    checked = check(plant, log)
    assert isinstance(checked, CheckResult)
    lags = res.to_dict()["current_sensor_lag"]
    assert lags["before"] == checked.free.current_lag > 0.3 and lags["after"] > 0.3
    assert res.before["current"] == pytest.approx(checked.free_run_rms["current"], rel=1e-9)
    log_path, params = tmp_path / "rig.csv", tmp_path / "motor.json"
    write_log_csv(log, log_path)
    params.write_text(json.dumps(case.nominal), encoding="utf-8")
    assert main(["fit", str(log_path), "--params", str(params), "--effects", "param:R",
                 "--out", str(tmp_path / "out.json")]) == 0
    assert "current read through the sensor's lag fitted, " in capsys.readouterr().out
