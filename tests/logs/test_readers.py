"""Readers on generated files of every format (tests/logfiles.py): the right channels, signs and units."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ocp.errors import LogError
from ocp.logs import Log, LogKind, ReadOptions, read_log, write_reference_mat
from tests.logfiles import (
    G0,
    RPM,
    Thruster,
    thruster_sweep,
    tyto_series,
    write_csv,
    write_dataflash,
    write_ulog,
    write_xlsx,
)


def _check_sweep(log: Log, cols: dict[str, np.ndarray]) -> None:
    sign = np.sign(cols["PWM (µs)"] - 1500)
    assert log.kind is LogKind.STEADY_STATE and log.electrical == "supply"
    np.testing.assert_allclose(log.omega, sign * cols["RPM"] * RPM, rtol=1e-12)
    np.testing.assert_allclose(log.thrust, cols["Force (N)"], rtol=1e-12)  # the SI column of the two
    np.testing.assert_allclose(log.current, cols["Current (A)"], rtol=1e-12)  # supply current: unsigned
    np.testing.assert_allclose(log.voltage, 16.0)
    assert log.command is not None
    np.testing.assert_allclose(log.command, (cols["PWM (µs)"] - 1500) / 400, rtol=1e-12)
    assert log.torque is None and not log.complete
    assert any("steady-state sweep" in n for n in log.notes) and any("sign taken from the command" in n
                                                                      for n in log.notes)


def test_vendor_sweep_csv_with_a_title_line_is_a_steady_sweep(tmp_path: Path) -> None:
    cols = thruster_sweep()
    write_csv(cols, tmp_path / "sweep.csv", title="Thruster performance at 16 V")
    _check_sweep(read_log(tmp_path / "sweep.csv"), cols)


def test_vendor_sweep_xlsx_reads_like_the_csv(tmp_path: Path) -> None:
    pytest.importorskip("openpyxl")
    cols = thruster_sweep()
    write_xlsx(cols, tmp_path / "sweep.xlsx", title="Thruster performance at 16 V")
    _check_sweep(read_log(tmp_path / "sweep.xlsx"), cols)


def test_force_in_kgf_only_is_converted(tmp_path: Path) -> None:
    cols = thruster_sweep()
    cols.pop("Force (N)")
    write_csv(cols, tmp_path / "kgf.csv")
    log = read_log(tmp_path / "kgf.csv")
    np.testing.assert_allclose(log.thrust, cols["Force (Kg f)"] * G0, rtol=1e-12)


def test_tyto_1585_header_reads_optical_speed_torque_and_supply(tmp_path: Path) -> None:
    cols, truth = tyto_series("1585")
    write_csv(cols, tmp_path / "tyto.csv")
    log = read_log(tmp_path / "tyto.csv", options=ReadOptions(pole_pairs=7))
    assert log.kind is LogKind.TIME_SERIES and log.electrical == "supply"
    np.testing.assert_allclose(log.omega, truth["omega"], rtol=1e-8, atol=1e-6)
    np.testing.assert_allclose(log.thrust, truth["thrust"], rtol=1e-8, atol=1e-9)
    assert log.torque is not None
    np.testing.assert_allclose(log.torque, truth["torque"], rtol=1e-8, atol=1e-12)
    assert any("not used" in n for n in log.notes)  # pole pairs given, but the optical speed is mechanical


def test_tyto_electrical_speed_needs_pole_pairs(tmp_path: Path) -> None:
    cols, truth = tyto_series("us-kg")
    write_csv(cols, tmp_path / "tyto.csv")
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "tyto.csv")
    assert err.value.field == "Motor Electrical Speed (RPM)" and "pole pairs" in err.value.reason
    log = read_log(tmp_path / "tyto.csv", options=ReadOptions(pole_pairs=7))
    np.testing.assert_allclose(log.omega, truth["omega"], rtol=1e-8, atol=1e-6)
    np.testing.assert_allclose(log.thrust, truth["thrust"], rtol=1e-8, atol=1e-9)  # kg -> kgf -> N
    assert log.command is not None
    np.testing.assert_allclose(log.command, (truth["esc"] - 1500) / 400, atol=1e-8)  # 10 digits in the file


def test_tyto_ozf_thrust_and_time_in_ms(tmp_path: Path) -> None:
    cols, truth = tyto_series("ozf")
    write_csv(cols, tmp_path / "tyto.csv")
    log = read_log(tmp_path / "tyto.csv")
    np.testing.assert_allclose(log.t, truth["t"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(log.thrust, truth["thrust"], rtol=1e-8, atol=1e-9)


def test_neutral_and_range_options_move_the_sign(tmp_path: Path) -> None:
    cols = thruster_sweep()
    write_csv(cols, tmp_path / "sweep.csv")
    log = read_log(tmp_path / "sweep.csv", options=ReadOptions(neutral_us=1600, throttle_range_us=(1100, 1900)))
    assert log.command is not None
    np.testing.assert_allclose(log.command, (cols["PWM (µs)"] - 1600) / 500, rtol=1e-12)


def test_irregular_time_is_resampled_and_said_or_refused(tmp_path: Path) -> None:
    cols, truth = tyto_series("1585")
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.03, 0.07, truth["t"].size))
    cols["Time (s)"] = t
    write_csv(cols, tmp_path / "jitter.csv")
    log = read_log(tmp_path / "jitter.csv")
    assert np.allclose(np.diff(log.t), np.diff(log.t)[0], rtol=1e-9)
    assert any("resampled onto a uniform" in n for n in log.notes)
    np.testing.assert_allclose(log.omega, np.interp(log.t, t, cols["Motor Optical Speed (RPM)"]) * RPM *
                               np.sign(np.interp(log.t, t, cols["ESC (µs)"]) - 1500), atol=2.0)
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "jitter.csv", options=ReadOptions(resample="refuse"))
    assert err.value.field == "t" and "irregular" in err.value.reason
    cols["Time (s)"] = np.where(np.arange(t.size) >= 100, t + 3.0, t)
    write_csv(cols, tmp_path / "gap.csv")
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "gap.csv")
    assert err.value.field == "t" and "gap of" in err.value.reason


def test_mat_log_in_and_reference_out(tmp_path: Path) -> None:
    from scipy import io as sio

    th = Thruster()
    pwm = np.linspace(1100, 1900, 17)
    w = th.speed(pwm)
    sio.savemat(tmp_path / "rig.mat", {"sweep": {"esc_us": pwm, "rpm": np.abs(w) / RPM, "thrust_kgf": th.thrust(w) / G0,
                                                 "voltage": 16 + 0 * pwm, "current": th.supply_power(w) / 16}})
    log = read_log(tmp_path / "rig.mat")
    assert log.kind is LogKind.STEADY_STATE
    np.testing.assert_allclose(log.omega, w, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(log.thrust, th.thrust(w), rtol=1e-9, atol=1e-12)
    t = np.linspace(0, 1, 11)
    write_reference_mat({"t": t, "thrust": np.sin(t), "omega": np.cos(t)}, tmp_path / "ref.mat")
    back = sio.loadmat(tmp_path / "ref.mat")
    assert back["t"].shape == (11, 1) and back["ref_ts"].shape == (11, 3)
    np.testing.assert_allclose(back["ref_ts"][:, 1], np.sin(t))


def _flight_truth(n: int = 300) -> dict[str, np.ndarray]:
    t = 1.0 + np.arange(n) * 0.02  # 50 Hz ESC telemetry
    u = 0.8 * np.sin(2 * np.pi * (t - 1.0) / 4.0)
    w = Thruster().speed(1500 + 400 * u)
    return {"t": t, "u": u, "rpm": np.abs(w) / RPM, "volts": 15.5 - 0.5 * np.abs(u), "amps": 10 * u**2 + 0.2}


def test_px4_ulog_esc_status_and_actuator_motors(tmp_path: Path) -> None:
    pytest.importorskip("pyulog")
    tr = _flight_truth()
    t_cmd = np.arange(0.99, tr["t"][-1] + 0.01, 0.01)  # 100 Hz command, other clock
    u_cmd = np.interp(t_cmd, tr["t"], tr["u"])
    write_ulog(tmp_path / "flight.ulg", tr["t"] * 1e6, np.round(tr["rpm"]), tr["volts"], tr["amps"], t_cmd * 1e6,
               u_cmd, motor=1)
    log = read_log(tmp_path / "flight.ulg", options=ReadOptions(motor=1))
    assert log.kind is LogKind.TIME_SERIES and log.electrical == "supply" and not log.has("thrust")
    k = np.round((log.t - 1.0) / 0.02).astype(int)  # the ESC grid, on which the command is interpolated
    assert log.n >= tr["t"].size - 2
    np.testing.assert_allclose(log.t, tr["t"][k], atol=1e-6)
    np.testing.assert_allclose(log.omega, np.sign(tr["u"][k]) * np.round(tr["rpm"][k]) * RPM, rtol=1e-4, atol=1e-3)
    np.testing.assert_allclose(log.voltage, tr["volts"][k], rtol=1e-6)
    np.testing.assert_allclose(log.current, tr["amps"][k], rtol=1e-6)
    assert any("no thrust" in n for n in log.notes)
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "flight.ulg", options=ReadOptions(motor=5))
    assert err.value.field == "esc_status"


def test_ardupilot_dataflash_esc_and_rcou(tmp_path: Path) -> None:
    pytest.importorskip("pymavlink")
    tr = _flight_truth()
    pwm = np.round(1500 + 400 * tr["u"])
    write_dataflash(tmp_path / "flight.bin", tr["t"] * 1e6, tr["rpm"], tr["volts"], tr["amps"], tr["t"] * 1e6 + 3000,
                    pwm, instance=0)
    log = read_log(tmp_path / "flight.bin")
    assert log.electrical == "supply" and not log.has("thrust")
    def at(y: np.ndarray) -> np.ndarray:  # the ESC channels on the merged grid (it starts at the first RCOU)
        return np.interp(log.t, tr["t"], y)

    assert log.t[0] == pytest.approx(1.003, abs=1e-6)
    np.testing.assert_allclose(log.voltage, at(np.round(100 * tr["volts"]) / 100), atol=1e-9)
    np.testing.assert_allclose(log.current, at(np.round(100 * tr["amps"]) / 100), atol=1e-9)
    sign = np.sign(at(pwm) - 1500)
    moving = np.abs(at(pwm) - 1500) > 30  # away from the reversals, where the command sign is settled
    np.testing.assert_allclose(log.omega[moving], (sign * at(np.round(100 * tr["rpm"]) / 100) * RPM)[moving],
                               rtol=1e-6)
    assert math.isclose(log.dt, 0.02, rel_tol=1e-6)



def test_optimize_out_mat_writes_a_simulink_reference(tmp_path: Path) -> None:
    """``thrustshape optimize --out ref.mat`` goes through clients.cli.io.write_csv: a .mat path gets MATLAB."""
    from scipy import io as sio

    from clients.cli.io import write_csv as cli_write

    t = np.linspace(0.0, 2.0, 101)
    cols = {"t": t, "thrust": 0.3 * np.sin(np.pi * t), "omega": np.cos(t), "voltage": 2 * t}
    cli_write(cols, str(tmp_path / "ref.mat"))
    m = sio.loadmat(tmp_path / "ref.mat")
    assert m["ref_ts"].shape == (101, 4) and m["t"].shape == (101, 1)
    for j, name in enumerate(str(m["ref_columns"][0]).split(",")):
        np.testing.assert_array_equal(m["ref_ts"][:, j], cols[name])


def test_tyto_proptest_export_one_way_esc(tmp_path: Path) -> None:
    """A Tyto "PropTest" export as the 1580/1585 software writes it (full header with accelerometers and
    efficiencies, one row per ESC step 1000..2000 us, 5.5 s apart, a one-way ESC, the torque cell's
    reaction sign negative): a sweep, AccX (g) is not a thrust, nothing signed, torque aligned with speed."""
    esc = np.arange(1000.0, 2001.0, 100.0)
    rpm = np.where(esc > 1000, 11.5 * (esc - 1000), 0.0)
    w = rpm * RPM
    header = ("Time (s),ESC signal (µs),Servo 1 (µs),Servo 2 (µs),Servo 3 (µs),AccX (g),AccY (g),AccZ (g),"
              "Torque (N·m),Thrust (kgf),Voltage (V),Current (A),Motor Electrical Speed (RPM),"
              "Motor Optical Speed (RPM),Electrical Power (W),Mechanical Power (W),Motor Efficiency (%),"
              "Propeller Mech. Efficiency (kgf/W),Overall Efficiency (kgf/W),Vibration (g),App message,")
    rows = [f"{0.24 + 5.5 * k},{esc[k]:.0f},,,,0.03,0.02,-0.98,{-6e-7 * w[k] ** 2},{5.2e-6 * w[k] ** 2 / G0},"
            f"16.0,{1e-5 * w[k] ** 1.5},{7 * rpm[k]},{rpm[k]},1,1,50,0.1,0.05,0.06,," for k in range(esc.size)]
    (tmp_path / "PropTest.csv").write_text("\ufeff" + header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    log = read_log(tmp_path / "PropTest.csv")
    assert log.kind is LogKind.STEADY_STATE and log.n == 11
    np.testing.assert_allclose(log.thrust, 5.2e-6 * w**2, rtol=1e-9, atol=1e-12)  # Thrust (kgf), not AccX (g)
    np.testing.assert_allclose(log.omega, w, rtol=1e-12)  # nothing signed: a one-way ESC
    assert log.torque is not None
    np.testing.assert_allclose(log.torque, 6e-7 * w**2, rtol=1e-9, atol=1e-15)
    assert any("one-way ESC" in n for n in log.notes) and any("sign flipped" in n for n in log.notes)


@pytest.mark.parametrize("hold", [1, 3])
def test_a_slow_sweep_up_and_back_down_is_asked_for_its_kind(hold: int, tmp_path: Path) -> None:
    """A thrust stand's sweep with a time column, rows 5.5 s apart, the ESC stepped up and back down (``hold`` rows a
    step): no longer strictly monotone, so not detected as a sweep; until session 72 it was read as a time series with
    a row every 5.5 s (refused later as too short, or checked as one). Now refused, naming the time column and both
    kinds; told either, it is read as that kind (the sweep with a row per step as logged)."""
    esc = np.repeat(np.concatenate([np.arange(1000.0, 2001.0, 50.0), np.arange(1950.0, 999.0, -50.0)]), hold)
    rpm = 11.5 * (esc - 1000)
    rows = [f"{5.5 * k:.2f},{e:.0f},{r:.1f},{5.2e-6 * (r * RPM) ** 2 / G0:.6g},16.0,{1e-5 * (r * RPM) ** 1.5:.6g}"
            for k, (e, r) in enumerate(zip(esc, rpm, strict=True))]
    path = tmp_path / "updown.csv"
    path.write_text("Time (s),ESC signal (µs),Motor Optical Speed (RPM),Thrust (kgf),Voltage (V),Current (A)\n"
                    + "\n".join(rows) + "\n", encoding="utf-8")
    with pytest.raises(LogError) as err:
        read_log(path)
    assert err.value.field == "Time (s)" and "5.5 s apart" in err.value.reason and "--steady-state" in err.value.reason
    sweep = read_log(path, kind="steady-state")
    assert sweep.kind is LogKind.STEADY_STATE and sweep.n == esc.size
    np.testing.assert_allclose(sweep.omega, rpm * RPM, rtol=1e-3)
    if esc.size >= 50:
        assert read_log(path, kind="time-series").kind is LogKind.TIME_SERIES
    else:  # (told it is a time series, a sweep of 41 rows is one too short to check)
        with pytest.raises(LogError, match="too short"):
            read_log(path, kind="time-series")


def test_a_time_in_ms_under_a_header_without_its_unit_is_not_read_as_seconds(tmp_path: Path) -> None:
    """A logger's millisecond counter under a bare ``t`` header (seconds by default): read as seconds it made a 1 kHz
    log a row a second. Refused, with the header that would say so; named ``time (ms)`` it is a 1 kHz time series."""
    n = 400
    t = np.arange(n, dtype=float)
    v = 6.0 * np.sin(2 * np.pi * 5.0 * t / 1000.0)
    cols = {"voltage": v, "current": 0.5 * v, "omega": 40.0 * v, "thrust": 1e-4 * (40.0 * v) ** 2}
    body = "\n".join(f"{t[k]:.0f}," + ",".join(f"{c[k]:.6g}" for c in cols.values()) for k in range(n)) + "\n"
    bare, named = tmp_path / "bare.csv", tmp_path / "named.csv"
    bare.write_text("t," + ",".join(cols) + "\n" + body, encoding="utf-8")
    named.write_text("time (ms)," + ",".join(cols) + "\n" + body, encoding="utf-8")
    with pytest.raises(LogError, match=r"time \(ms\)") as err:
        read_log(bare)
    assert err.value.field == "t" and "1 s apart" in err.value.reason
    log = read_log(named)
    assert log.kind is LogKind.TIME_SERIES and log.dt == pytest.approx(1e-3)
