"""Log readers: SI CSV/Parquet, column maps with units, Tyto exports, steady-state sweeps, clear errors."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from ocp.errors import LogError
from ocp.logs import LogKind, read_log

N = 200


def _write_csv(path: Path, cols: dict[str, np.ndarray]) -> None:
    lines = [",".join(cols)] + [",".join(repr(float(c[k])) for c in cols.values()) for k in range(len(next(iter(
        cols.values()))))]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def _si() -> dict[str, np.ndarray]:
    t = np.arange(N) * 1e-3
    w = 30.0 * np.sin(2 * np.pi * 2 * t)
    return {"t": t, "voltage": 2.0 * np.sin(2 * np.pi * 2 * t), "current": 0.1 * np.cos(t), "omega": w,
            "thrust": 1.4e-4 * w * np.abs(w), "extra": np.ones(N)}


def test_si_csv_and_parquet_read_identically(tmp_path: Path) -> None:
    cols = _si()
    _write_csv(tmp_path / "a.csv", cols)
    pq.write_table(pa.table(cols), tmp_path / "a.parquet")
    a, b = read_log(tmp_path / "a.csv"), read_log(tmp_path / "a.parquet")
    for k in ("t", "voltage", "current", "omega", "thrust"):
        np.testing.assert_allclose(getattr(a, k), cols[k], rtol=0, atol=0)
        np.testing.assert_allclose(getattr(b, k), cols[k], rtol=0, atol=0)
    assert a.theta is None and a.dt == pytest.approx(1e-3)


def test_column_map_converts_units(tmp_path: Path) -> None:
    si = _si()
    cols = {"time_ms": si["t"] * 1e3, "V": si["voltage"], "I_mA": si["current"] * 1e3,
            "speed_rpm": si["omega"] * 60 / (2 * math.pi), "F_gf": si["thrust"] / 9.80665e-3}
    _write_csv(tmp_path / "b.csv", cols)
    cmap = {"t": {"column": "time_ms", "unit": "ms"}, "voltage": "V", "current": {"column": "I_mA", "unit": "mA"},
            "omega": {"column": "speed_rpm", "unit": "rpm"}, "thrust": {"column": "F_gf", "unit": "gf"}}
    log = read_log(tmp_path / "b.csv", cmap)
    for k in ("t", "voltage", "current", "omega", "thrust"):
        np.testing.assert_allclose(getattr(log, k), si[k], rtol=1e-12, atol=1e-12)


def test_theta_only_log_differentiates_speed(tmp_path: Path) -> None:
    si = _si()
    theta = -30.0 / (2 * np.pi * 2) * np.cos(2 * np.pi * 2 * si["t"])
    _write_csv(tmp_path / "c.csv", {"t": si["t"], "voltage": si["voltage"], "current": si["current"],
                                    "theta": theta, "thrust": si["thrust"]})
    log = read_log(tmp_path / "c.csv")
    np.testing.assert_allclose(log.omega[1:-1], si["omega"][1:-1], atol=0.01)


def test_tyto_export_takes_the_speed_sign_from_the_esc_command(tmp_path: Path) -> None:
    t = np.arange(N) * 0.01
    esc = 1500 + 400 * np.sin(2 * np.pi * 0.5 * t)
    rpm = np.abs(esc - 1500) * 5.0
    header = ("Time (s),ESC signal (µs),Servo 1 (µs),Torque (N·m),Thrust (kgf),Voltage (V),Current (A),"
              "Motor Electrical Speed (RPM),Motor Optical Speed (RPM),Electrical Power (W)")
    rows = [f"{t[k]},{esc[k]},1500,0,{0.01 * np.sign(esc[k] - 1500)},12.0,{abs(esc[k] - 1500) / 400},"
            f"{7 * rpm[k]},{rpm[k]},0" for k in range(N)]
    (tmp_path / "tyto.csv").write_text(header + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    log = read_log(tmp_path / "tyto.csv")
    sign = np.sign(esc - 1500)
    np.testing.assert_allclose(log.omega, sign * rpm * 2 * math.pi / 60, rtol=1e-12)
    np.testing.assert_allclose(log.thrust, 0.01 * 9.80665 * sign, rtol=1e-12)
    # the export's voltage and current are the supply's (issue #13): kept as measured, flagged, never
    # turned into an armature voltage by the duty
    assert log.electrical == "supply"
    np.testing.assert_allclose(log.voltage, 12.0, rtol=0)
    np.testing.assert_allclose(log.current, np.abs(esc - 1500) / 400, rtol=1e-12)


def test_steady_state_sweep_needs_no_time(tmp_path: Path) -> None:
    w = np.linspace(-50, 50, 9)
    _write_csv(tmp_path / "s.csv", {"voltage": w * 0.06, "current": w * 0.001, "omega": w,
                                    "thrust": 1.4e-4 * w * np.abs(w)})
    log = read_log(tmp_path / "s.csv", kind=LogKind.STEADY_STATE)
    assert log.kind is LogKind.STEADY_STATE and log.n == 9
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "s.csv")
    assert err.value.field == "t"


@pytest.mark.parametrize(("mutate", "field", "words"), [
    (lambda c: c.__setitem__("thrust", np.where(np.arange(N) == 7, np.nan, c["thrust"])), "thrust", "NaN"),
    (lambda c: c.__setitem__("t", c["t"][::-1].copy()), "t", "increasing"),
    (lambda c: [c.__setitem__(k, v[:10]) for k, v in list(c.items())], "t", "too short"),
    (lambda c: (c.pop("omega")), "omega", "omega or theta"),
])
def test_bad_logs_raise_log_errors_naming_the_column(tmp_path: Path, mutate: Callable[[dict[str, np.ndarray]], object],
                                                      field: str, words: str) -> None:
    cols = _si()
    mutate(cols)
    _write_csv(tmp_path / "bad.csv", cols)
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "bad.csv")
    assert err.value.field == field and words in err.value.reason


def test_unknown_unit_is_an_error_naming_the_column(tmp_path: Path) -> None:
    _write_csv(tmp_path / "u.csv", _si())
    with pytest.raises(LogError) as err:
        read_log(tmp_path / "u.csv", {"omega": {"column": "omega", "unit": "furlong/s"}})
    assert err.value.field == "omega" and "furlong" in err.value.reason


def test_a_missing_current_is_absent_not_an_error(tmp_path: Path) -> None:
    """Issue #13: a log lacking a channel disables only what needs it (the reader no longer refuses it)."""
    cols = _si()
    cols.pop("current")
    _write_csv(tmp_path / "nocur.csv", cols)
    log = read_log(tmp_path / "nocur.csv")
    assert not log.has("current") and log.has("thrust") and log.has("voltage") and not log.complete
    assert np.all(np.isnan(log.current)) and "current" not in log.columns()


def test_irregular_arrays_are_refused_not_integrated_on_a_median_step() -> None:
    from ocp.logs import log_from_arrays

    t = np.cumsum(np.where(np.arange(N) % 2 == 0, 1e-3, 1.5e-3))
    with pytest.raises(LogError) as err:
        log_from_arrays(t, np.ones(N), np.ones(N), np.ones(N), omega=np.ones(N))
    assert err.value.field == "t" and "irregular" in err.value.reason
