"""Point-by-point checks (ocp.identify.steady, ocp.identify.equations) on generated ESC sweeps, Tyto
series and flight logs whose truth comes from tests/logfiles.py's own formulas."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from ocp.errors import LogError
from ocp.identify import check, diagnose, fit
from ocp.identify.equations import TIME_EFFECTS
from ocp.identify.estimate import peak_torque
from ocp.identify.steady import PointCheck
from ocp.identify.steady_diagnose import PointDiagnosis
from ocp.logs import ReadOptions, read_log
from ocp.model.effects import load_plant
from tests.logfiles import RPM, Thruster, thruster_sweep, tyto_series, write_csv, write_ulog


def _named(d: dict[str, Any]) -> set[str]:
    """Every effect named anywhere in a diagnosis (verdict and every round's ranking)."""
    return set(d["verdict"]) | {e["effect"] for r in d["rounds"] for e in r["ranking"]}


@pytest.mark.parametrize(("ratio", "seed", "c_f_nominal"), [(0.78, 1, None), (0.86, 5, None), (0.70, 9, 2.6e-4)])
def test_sweep_verdict_recovers_the_thrust_asymmetry_ratio(tmp_path: Path, ratio: float, seed: int,
                                                           c_f_nominal: float | None) -> None:
    th = Thruster(ratio=ratio)
    write_csv(thruster_sweep(th, seed=seed), tmp_path / "sweep.csv", title="Thruster performance")
    params = th.params() | ({"c_f": c_f_nominal} if c_f_nominal else {})
    res = diagnose(load_plant(params), read_log(tmp_path / "sweep.csv"))
    assert isinstance(res, PointDiagnosis)
    d = res.to_dict()
    assert "thrust_asymmetry" in d["verdict"]
    assert abs(d["fitted_maps"]["thrust_ratio_reverse_to_forward"] - ratio) < 0.02
    assert abs(d["maps"]["thrust"]["ratio_reverse_to_forward"] - ratio) < 0.02  # the plant-free estimate too
    assert not _named(d) & TIME_EFFECTS  # no time effect is ever a candidate on a sweep
    if c_f_nominal:
        assert "param:c_f" in d["verdict"]
    checked = {e["equation"]: e["checked"] for e in d["equations"]}
    assert checked == {"thrust": True, "mechanical": False, "electrical": False, "power": True}


def test_symmetric_sweep_with_the_true_plant_has_nothing_missing(tmp_path: Path) -> None:
    th = Thruster(ratio=1.0)
    write_csv(thruster_sweep(th), tmp_path / "sym.csv")
    d = diagnose(load_plant(th.params()), read_log(tmp_path / "sym.csv")).to_dict()
    assert d["verdict"] == [] and d["message"] == "nothing missing"
    assert abs(d["maps"]["thrust"]["ratio_reverse_to_forward"] - 1.0) < 0.02


class _DragAsymmetric(Thruster):
    """Reverse rotation drags 1.4x (power goes up in reverse only)."""

    def supply_power(self, w: np.ndarray) -> np.ndarray:
        c = np.where(w >= 0, self.c_tau, 1.4 * self.c_tau)
        tau = self.B * w + c * w * np.abs(w)
        return (tau * w + self.R * (tau / self.k_t) ** 2) / self.eta + self.p0


def test_power_balance_finds_a_reverse_drag_asymmetry(tmp_path: Path) -> None:
    th = _DragAsymmetric(ratio=1.0)
    write_csv(thruster_sweep(th), tmp_path / "drag.csv")
    res = check(load_plant(th.params()), read_log(tmp_path / "drag.csv"))
    assert isinstance(res, PointCheck)
    by_dir = res.to_dict()["breakdown"]["direction"]["power"]
    assert by_dir["reverse"]["mean"] > 0 > by_dir["forward"]["mean"]  # the model under-predicts reverse power
    d = diagnose(load_plant(th.params()), read_log(tmp_path / "drag.csv")).to_dict()
    assert d["verdict"][:1] == ["drag_asymmetry"]
    dc = d["ranking"][0]["parameters"]["dc_tau"]
    assert dc == pytest.approx(0.4 * th.c_tau, rel=0.05)
    assert abs(d["maps"]["power"]["ratio_reverse_to_forward"] - 1.0) > 0.3
    assert not _named(d) & TIME_EFFECTS


def test_sweep_fit_and_refusal_of_time_effects(tmp_path: Path) -> None:
    th = Thruster(ratio=0.8)
    write_csv(thruster_sweep(th), tmp_path / "sweep.csv")
    log = read_log(tmp_path / "sweep.csv")
    res = fit(load_plant(th.params()), log, ["thrust_asymmetry"])
    dc = dict(zip(res.names, res.values, strict=True))["thrust_asymmetry.dc_f"]
    assert (th.c_f + dc) / th.c_f == pytest.approx(0.8, abs=0.02)
    assert res.after["thrust"] < 0.2 * res.before["thrust"]
    assert res.adopted and [e.name for e in res.plant.effects] == ["thrust_asymmetry"]
    with pytest.raises(LogError) as err:
        fit(load_plant(th.params()), log, ["thrust_lag"])
    assert err.value.field == "effects" and "needs time" in err.value.reason


def test_a_sweep_fit_the_log_cannot_show_is_not_adopted(tmp_path: Path) -> None:
    """A stand swept forward only holds nothing of a thrust asymmetry (it acts in reverse): the fit leaves the
    residuals as they were, and the calibrated plant is the starting one, with the reason (as ``fit`` on a time
    series, where the free run decides)."""
    th = Thruster(ratio=0.8)
    rows = thruster_sweep(th)
    forward = rows["PWM (µs)"] > 1525.0
    write_csv({k: v[forward] for k, v in rows.items()}, tmp_path / "forward.csv", title="Thruster at 16 V")
    res = fit(load_plant(th.params()), read_log(tmp_path / "forward.csv"), ["thrust_asymmetry"])
    assert res.after == res.before and not res.adopted and res.plant.effects == ()
    assert res.note is not None and "no better than the starting plant" in res.note
    assert res.to_dict()["adopted"] is False and res.calibrated()["notes"]["adopted"] is False


def test_a_sweep_whose_thrust_opposes_its_speed_is_refused_naming_the_thrust(tmp_path: Path) -> None:
    """A stand whose load cell pushes (the thrust column negated): no catalogue effect turns the thrust map's sign,
    so diagnose, check and fit refuse it on the thrust (before: ``c_f``, a thrust asymmetry and a force offset at
    78-93 noise units); read back with ``negate``, it is the sweep it was."""
    th = Thruster(ratio=0.8)
    rows = thruster_sweep(th)
    write_csv(dict(rows, **{k: -v for k, v in rows.items() if k.startswith("Force")}), tmp_path / "pushed.csv",
              title="Thruster at 16 V")
    plant = load_plant(th.params())
    log = read_log(tmp_path / "pushed.csv")
    for op in (lambda: diagnose(plant, log), lambda: check(plant, log), lambda: fit(plant, log, ["thrust_asymmetry"])):
        with pytest.raises(LogError) as err:
            op()
        assert err.value.field == "thrust" and "--negate thrust" in err.value.reason
    back = read_log(tmp_path / "pushed.csv", options=ReadOptions(negate=("thrust",)))
    assert diagnose(plant, back).to_dict()["verdict"] == ["thrust_asymmetry"]


def test_tyto_series_checks_torque_from_the_cell_and_thrust(tmp_path: Path) -> None:
    cols, _ = tyto_series("1585")
    write_csv(cols, tmp_path / "tyto.csv")
    log = read_log(tmp_path / "tyto.csv")
    c = check(load_plant(Thruster().params()), log).to_dict()
    eq = {e["equation"]: e for e in c["equations"]}
    assert eq["mechanical"]["checked"] and "torque" in eq["mechanical"]["uses"]
    assert not eq["electrical"]["checked"] and "supply" in eq["electrical"]["reason"]
    # the true torque map: the residual is the J w' term the generator leaves out, small against the torque
    assert c["one_step"]["rms"]["mechanical"] < 0.05 * float(np.sqrt(np.mean(log.torque**2)))  # type: ignore[operator]
    d = diagnose(load_plant(Thruster().params()), log).to_dict()
    assert "thrust_asymmetry" in d["verdict"] and not _named(d) & TIME_EFFECTS


def test_flight_log_has_no_thrust_equation_and_says_why(tmp_path: Path) -> None:
    pytest.importorskip("pyulog")
    th = Thruster()
    t = 1.0 + np.arange(400) * 0.02
    u = 0.8 * np.sin(2 * np.pi * (t - 1.0) / 4.0)
    w = th.speed(1500 + 400 * u)
    volts = 15.8 + 0 * t
    write_ulog(tmp_path / "f.ulg", t * 1e6, np.abs(w) / RPM, volts, th.supply_power(w) / volts, t * 1e6, u, motor=0)
    log = read_log(tmp_path / "f.ulg", options=ReadOptions(motor=0))
    res = check(load_plant(th.params()), log)
    d = res.to_dict()
    eq = {e["equation"]: e for e in d["equations"]}
    assert not eq["thrust"]["checked"] and "no thrust" in eq["thrust"]["reason"]
    assert eq["power"]["checked"] and "thrust" not in d["one_step"]["rms"]
    assert d["drive"]["efficiency"] == pytest.approx(th.eta, rel=0.05)
    dd = diagnose(load_plant(th.params()), log).to_dict()
    names = _named(dd)
    assert not names & TIME_EFFECTS and not names & {"thrust_asymmetry", "force_offset", "param:c_f"}


def test_armature_sweep_checks_all_three_equations_and_finds_friction(tmp_path: Path) -> None:
    """A DC-motor sweep with the armature's voltage and current (no ESC): steady state from its own closed
    form with a Coulomb friction the model lacks; the sweep is told (no time column, no command)."""
    p = {"J": 2.7e-5, "B": 5.3e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573, "k_e": 0.0573, "R": 5.0, "L": 2e-3}
    tau_c = 0.004
    w = np.concatenate([np.linspace(-60, -5, 12), np.linspace(5, 60, 12)])
    i = (p["B"] * w + p["c_tau"] * w * np.abs(w) + tau_c * np.sign(w)) / p["k_t"]  # k_t i = load + friction
    v = p["R"] * i + p["k_e"] * w
    write_csv({"voltage": v, "current": i, "omega": w, "thrust": p["c_f"] * w * np.abs(w)}, tmp_path / "arm.csv")
    log = read_log(tmp_path / "arm.csv", kind="steady-state")
    d = diagnose(load_plant(p), log).to_dict()
    assert {e["equation"]: e["checked"] for e in d["equations"]} == {
        "thrust": True, "mechanical": True, "electrical": True, "power": False}
    assert d["verdict"][:1] == ["coulomb_friction"]
    assert d["ranking"][0]["parameters"]["tau_c"] == pytest.approx(tau_c, rel=0.02)
    assert not _named(d) & TIME_EFFECTS
    from ocp.identify.report import html_report

    page = html_report(check(load_plant(p), log), log, plant=load_plant(p))
    assert "not checked" in page and "power" in page and page.count("data:image/png;base64,") == 1


def test_a_large_motors_friction_is_fitted_beyond_the_catalogues_box(tmp_path: Path) -> None:
    """The armature sweep above on a 500 W drive (k 0.5 N m/A) with 0.4 N m of Coulomb friction, four times the
    catalogue's 0.1 N m box (a small motor's): before session 40 the point fits held it at the box, ``fit`` returned
    0.1 and ``diagnose`` named ``k_t``, ``c_tau`` and Stribeck friction instead. Torque-valued boxes reach the
    motor's torque in the log (k_t times the largest current, 1.6 N m here)."""
    p = {"J": 2e-3, "B": 2e-3, "c_tau": 1e-4, "c_f": 4e-3, "k_t": 0.5, "k_e": 0.5, "R": 0.5, "L": 2e-3}
    tau_c = 0.4
    w = np.concatenate([np.linspace(-100, -5, 12), np.linspace(5, 100, 12)])
    i = (p["B"] * w + p["c_tau"] * w * np.abs(w) + tau_c * np.sign(w)) / p["k_t"]
    write_csv({"voltage": p["R"] * i + p["k_e"] * w, "current": i, "omega": w, "thrust": p["c_f"] * w * np.abs(w)},
              tmp_path / "big.csv")
    log = read_log(tmp_path / "big.csv", kind="steady-state")
    d = diagnose(load_plant(p), log).to_dict()
    assert d["verdict"] == ["coulomb_friction"]
    assert d["ranking"][0]["parameters"]["tau_c"] == pytest.approx(tau_c, rel=0.02)
    res = fit(load_plant(p), log, ["coulomb_friction"])
    assert res.values[0] == pytest.approx(tau_c, rel=0.02)


def test_the_torque_scale_of_a_sweep_without_current_is_the_drag_at_its_peak_speed(tmp_path: Path) -> None:
    """Oracle, closed form: an ESC sweep logs speed and thrust only (no current, no torque cell); the boxes' torque
    scale is then the plant's drag ``B w + c_tau w^2`` at the peak speed."""
    th = Thruster()
    cols = {k: v for k, v in thruster_sweep(th).items() if k in ("PWM (µs)", "RPM", "Voltage (V)", "Force (N)")}
    write_csv(cols, tmp_path / "s.csv")
    log = read_log(tmp_path / "s.csv")
    plant = load_plant(th.params())
    assert np.all(np.isnan(log.current)) and log.torque is None
    w = float(np.max(np.abs(log.omega)))
    assert peak_torque(plant, log) == pytest.approx(plant.params.B * w + plant.params.c_tau * w * w, rel=1e-12)


def test_a_time_effect_asked_for_by_name_on_a_sweep_is_refused(tmp_path: Path) -> None:
    from ocp.errors import ParameterError
    from ocp.identify import DiagnoseOptions

    th = Thruster()
    write_csv(thruster_sweep(th), tmp_path / "s.csv")
    with pytest.raises(ParameterError) as err:
        diagnose(load_plant(th.params()), read_log(tmp_path / "s.csv"), DiagnoseOptions(candidates=("input_delay",)))
    assert err.value.field == "input_delay" and "time effects" in err.value.reason
