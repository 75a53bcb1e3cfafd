"""Generated log files in every format ocp.logs reads, from a *truth* computed here with its own
formulas (never ocp's): a brushless thruster on a bidirectional ESC, swept or flown.

* :func:`thruster_sweep` -- steady operating points per PWM step (closed-form steady speed of the DC
  motor equivalent, thrust ``c_f w^2`` forward and ``ratio c_f w^2`` reverse, supply power through an
  ESC of efficiency ``eta`` with idle power ``p0``);
* writers: vendor-like CSV/xlsx, Tyto/RCbenchmark CSV, MATLAB .mat; PX4 ULog and ArduPilot DataFlash
  built byte by byte from their documented formats (docs.px4.io "ULog File Format",
  ardupilot.org "Onboard Log" / LogStructure.h FMT layout).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

G0 = 9.80665
RPM = 2 * math.pi / 60


@dataclass(frozen=True)
class Thruster:
    """DC-motor equivalent of a small ROV thruster at 16 V (SI)."""

    c_f: float = 3.4e-4  # forward thrust coefficient [N s^2/rad^2]
    ratio: float = 0.78  # reverse / forward thrust coefficient
    c_tau: float = 5.0e-6  # drag torque coefficient [N m s^2/rad^2]
    B: float = 1.0e-5
    k_t: float = 0.03
    k_e: float = 0.03
    R: float = 0.12
    supply: float = 16.0  # [V]
    eta: float = 0.92  # ESC efficiency
    p0: float = 1.5  # ESC idle power [W]
    neutral: float = 1500.0
    half: float = 400.0
    deadband: float = 25.0  # [us] each side of neutral

    def params(self) -> dict[str, float]:
        return {"J": 4e-5, "B": self.B, "c_tau": self.c_tau, "c_f": self.c_f, "k_t": self.k_t, "k_e": self.k_e,
                "R": self.R, "L": 5e-5}

    def speed(self, pwm: np.ndarray) -> np.ndarray:
        """Steady speed [rad/s]: k_t (V_a - k_e w)/R = B w + c_tau w|w|, V_a = duty * supply (closed form)."""
        duty = np.where(np.abs(pwm - self.neutral) <= self.deadband, 0.0, (pwm - self.neutral) / self.half)
        va = duty * self.supply
        b = self.B + self.k_t * self.k_e / self.R
        c = self.k_t * np.abs(va) / self.R
        w = (-b + np.sqrt(b * b + 4 * self.c_tau * c)) / (2 * self.c_tau)
        return np.sign(va) * w

    def thrust(self, w: np.ndarray) -> np.ndarray:
        return np.where(w >= 0, self.c_f, self.ratio * self.c_f) * w * np.abs(w)

    def supply_power(self, w: np.ndarray) -> np.ndarray:
        tau = self.B * w + self.c_tau * w * np.abs(w)
        return (tau * w + self.R * (tau / self.k_t) ** 2) / self.eta + self.p0


def thruster_sweep(th: Thruster = Thruster(), step: float = 25.0, seed: int = 1) -> dict[str, np.ndarray]:
    """One row per PWM step 1100..1900 us: pwm [us], unsigned rpm, current [A], voltage [V], power [W],
    force [kgf] and [N] (signed), efficiency [g/W]; 0.3 % noise on the measured columns."""
    rng = np.random.default_rng(seed)
    pwm = np.arange(1100.0, 1900.0 + step / 2, step)
    w = th.speed(pwm)
    f = th.thrust(w) * (1 + 0.003 * rng.standard_normal(pwm.size))
    p = th.supply_power(w) * (1 + 0.003 * rng.standard_normal(pwm.size))
    volts = th.supply * np.ones_like(pwm)
    return {"PWM (µs)": pwm, "RPM": np.round(np.abs(w) / RPM), "Current (A)": np.round(p / volts, 2),
            "Voltage (V)": volts, "Power (W)": np.round(p, 1), "Force (Kg f)": np.round(f / G0, 4),
            "Efficiency (g/W)": np.round(np.abs(f) / G0 * 1000 / p, 2), "Force (N)": np.round(f, 3)}


def write_csv(cols: dict[str, np.ndarray], path: Path, title: str | None = None) -> None:
    lines = ([title] if title else []) + [",".join(cols)]
    n = len(next(iter(cols.values())))
    lines += [",".join(f"{float(c[k]):.10g}" for c in cols.values()) for k in range(n)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")


def write_xlsx(cols: dict[str, np.ndarray], path: Path, title: str | None = None) -> None:
    import openpyxl

    wb = openpyxl.Workbook()
    ws = wb.active
    if title:
        ws.append([title])
        ws.append([])
    ws.append(list(cols))
    n = len(next(iter(cols.values())))
    for k in range(n):
        ws.append([float(c[k]) for c in cols.values()])
    wb.save(path)


def tyto_series(header_variant: str = "1585", n: int = 400, seed: int = 2) -> tuple[dict[str, np.ndarray], dict]:
    """A Tyto/RCbenchmark time series (esc ramps both ways at 20 Hz) and its truth (SI)."""
    th = Thruster()
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.05
    esc = 1500 + 380 * np.sin(2 * np.pi * t / t[-1])
    w = th.speed(esc)
    f = th.thrust(w)
    tau = th.B * w + th.c_tau * w * np.abs(w)
    cur = th.supply_power(w) / th.supply
    pp = 7
    truth = {"t": t, "omega": w, "thrust": f, "torque": tau, "current": cur, "esc": esc}
    rpm = np.abs(w) / RPM
    if header_variant == "1585":  # the header, thrust in N, torque signed
        cols = {"Time (s)": t, "ESC (µs)": esc, "Servo (µs)": 1500 + 0 * t, "Torque (N·m)": tau, "Thrust (N)": f,
                "Voltage (V)": th.supply + 0 * t, "Current (A)": cur, "Motor Optical Speed (RPM)": rpm,
                "Motor Electrical Speed (RPM)": pp * rpm, "Electrical Power (W)": cur * th.supply}
    elif header_variant == "us-kg":  # (us), thrust in kg, torque Nm, electrical speed only
        cols = {"Time (s)": t, "ESC signal (us)": esc, "Torque (Nm)": tau, "Thrust (kg)": f / G0,
                "Voltage (V)": th.supply + 0 * t, "Current (A)": cur, "Motor Electrical Speed (RPM)": pp * rpm}
    else:  # ozf thrust, gf in another column ignored? no: one force column; time in ms as name_unit
        cols = {"time_ms": t * 1e3, "ESC (µs)": esc, "Thrust (ozf)": f / (4.4482216152605 / 16),
                "Voltage (V)": th.supply + 0 * t, "Current (A)": cur, "Motor Optical Speed (RPM)": rpm}
    del rng
    return cols, truth


# ---------------------------------------------------------------- PX4 ULog (docs.px4.io, ULog File Format)

def _ulog_msg(kind: str, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def write_ulog(path: Path, t_us: np.ndarray, rpm: np.ndarray, volts: np.ndarray, amps: np.ndarray,
               t_cmd_us: np.ndarray, control: np.ndarray, motor: int = 1) -> None:
    """A ULog with esc_status (two ESCs, ``motor`` carrying the data) and actuator_motors."""
    out = bytearray(b"ULog\x01\x12\x35" + bytes([1]) + struct.pack("<Q", 0))
    out += _ulog_msg("B", bytes(16) + struct.pack("<3Q", 0, 0, 0))
    out += _ulog_msg("F", b"esc_report:uint64_t timestamp;int32_t esc_rpm;float esc_voltage;float esc_current;"
                          b"uint8_t[4] _padding0;")
    out += _ulog_msg("F", b"esc_status:uint64_t timestamp;uint8_t esc_count;uint8_t[7] _padding0;esc_report[2] esc;")
    out += _ulog_msg("F", b"actuator_motors:uint64_t timestamp;uint64_t timestamp_sample;uint16_t reversible_flags;"
                          b"uint8_t[2] _padding0;float[4] control;")
    out += _ulog_msg("I", bytes([len(b"char[3] ver")]) + b"char[3] ver" + b"1.0")
    out += _ulog_msg("A", struct.pack("<BH", 0, 0) + b"esc_status")
    out += _ulog_msg("A", struct.pack("<BH", 0, 1) + b"actuator_motors")
    events = [(round(t), 0, k) for k, t in enumerate(t_us)] + [(round(t), 1, k) for k, t in enumerate(t_cmd_us)]
    for t, which, k in sorted(events):
        if which == 0:
            reports = b""
            for m in range(2):
                on = m == motor
                reports += struct.pack("<QiffI", t, int(rpm[k]) if on else 0, float(volts[k]) if on else 0.0,
                                       float(amps[k]) if on else 0.0, 0)
            out += _ulog_msg("D", struct.pack("<HQB7x", 0, t, 2) + reports)
        else:
            ctl = [0.0] * 4
            ctl[motor] = float(control[k])
            out += _ulog_msg("D", struct.pack("<HQQH2x4f", 1, t, t, 0xF, *ctl))
    path.write_bytes(bytes(out))


# ---------------------------------------------------------------- ArduPilot DataFlash (LogStructure.h)

def _df(msg_type: int, payload: bytes) -> bytes:
    return bytes([0xA3, 0x95, msg_type]) + payload


def _fmt(msg_type: int, name: str, fmt: str, columns: str, size: int) -> bytes:
    return _df(0x80, struct.pack("<BB4s16s64s", msg_type, 3 + size, name.encode(), fmt.encode(), columns.encode()))


def write_dataflash(path: Path, t_us: np.ndarray, rpm: np.ndarray, volts: np.ndarray, amps: np.ndarray,
                    t_out_us: np.ndarray, pwm: np.ndarray, instance: int = 0) -> None:
    """A DataFlash .bin with ESC (format QBeCCcH: RPM int32*100, Volt/Curr uint16*100) and RCOU (C1..C14 us)."""
    esc_size = struct.calcsize("<QBiHHhH")
    rc_size = struct.calcsize("<Q14H")
    out = bytearray(_fmt(0x80, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns", 86))
    out += _fmt(150, "ESC", "QBeCCcH", "TimeUS,Instance,RPM,Volt,Curr,Temp,CTot", esc_size)
    out += _fmt(151, "RCOU", "Q" + "H" * 14, "TimeUS," + ",".join(f"C{k}" for k in range(1, 15)), rc_size)
    events = [(round(t), 0, k) for k, t in enumerate(t_us)] + [(round(t), 1, k) for k, t in enumerate(t_out_us)]
    for t, which, k in sorted(events):
        if which == 0:
            for inst in (instance, instance + 1):  # a second ESC with other data, to be ignored
                on = inst == instance
                out += _df(150, struct.pack("<QBiHHhH", t, inst, round(100 * rpm[k]) if on else 123,
                                            round(100 * volts[k]), round(100 * amps[k]) if on else 999, 2500, 0))
        else:
            ch = [1500] * 14
            ch[instance] = int(pwm[k])
            out += _df(151, struct.pack("<Q14H", t, *ch))
    path.write_bytes(bytes(out))
