"""A command held between jittered rows is put on the uniform grid by its mean over each step: its integral (the
drive's volt-seconds) kept at every grid point, checked against a brute-force integral; sampled channels stay
linearly interpolated."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ocp.logs import read_log
from ocp.logs.timebase import held_mean, merge, uniform


def _jittered(n: int, dt: float, seed: int) -> np.ndarray:
    """(n,) sample instants [s]: a grid of step ``dt`` with up to 30 % of a step of jitter (the first at 0)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt + np.clip(rng.normal(0.0, 0.1 * dt, n), -0.3 * dt, 0.3 * dt)
    t[0] = 0.0
    return t


def _brute_mean(grid: np.ndarray, t: np.ndarray, v: np.ndarray, per_step: int = 4000) -> np.ndarray:
    """(N,) the held signal's mean over each grid step by the midpoint rule on ``per_step`` points (the held value
    at a time: the row at or before it)."""
    h = grid[1] - grid[0]
    x = grid[:, None] + (np.arange(per_step) + 0.5) / per_step * h  # (N, per_step)
    return v[np.clip(np.searchsorted(t, x, side="right") - 1, 0, t.size - 1)].mean(axis=1)


def test_held_mean_keeps_the_held_signals_integral() -> None:
    t = _jittered(400, 1e-3, 0)
    v = np.repeat(np.random.default_rng(1).choice([-6.0, 2.0, 9.0], 80), 5)  # a PRBS of 5-row bits [V]
    h = float(np.median(np.diff(t)))
    grid = t[0] + h * np.arange(399)
    got = held_mean(grid, h, t, v)
    np.testing.assert_allclose(got, _brute_mean(grid, t, v), atol=9.0 * 2 / 4000)  # (the midpoint rule's step)
    # a level held on rows stays that level; on the rows' own regular grid each row is its own value
    assert np.all(held_mean(grid, h, t, np.full(t.size, 3.1)) == 3.1)  # (exactly: a one-level command has no steps)
    regular = np.arange(50) * 1e-3
    np.testing.assert_allclose(held_mean(regular, 1e-3, regular, v[:50]), v[:50], rtol=1e-12, atol=1e-12)


def test_a_jittered_files_command_is_held_its_sensors_interpolated(tmp_path: Path) -> None:
    """An armature log whose rows were taken at jittered instants: the voltage column (the drive's command, held
    to the next row) by its mean over each grid step, a sampled channel interpolated, and the note says both;
    linear interpolation would have put a ramp into every step of the command (checked to differ)."""
    t = _jittered(600, 1e-3, 2)
    rng = np.random.default_rng(3)
    v = np.repeat(rng.choice([-5.0, 5.0], 60), 10)
    cols = {"t": t, "voltage": v, "current": v / 2.0 + 0.01 * rng.standard_normal(t.size),
            "omega": 50.0 * np.sin(7.0 * t), "thrust": 0.1 * np.sin(7.0 * t) ** 2}
    np.savetxt(tmp_path / "jitter.csv", np.column_stack(list(cols.values())), delimiter=",",
               header=",".join(cols), comments="", fmt="%.12g")
    log = read_log(tmp_path / "jitter.csv")
    assert np.allclose(np.diff(log.t), log.dt, rtol=1e-9)
    np.testing.assert_allclose(log.voltage, _brute_mean(log.t, t, v), atol=10.0 / 4000)
    np.testing.assert_allclose(log.omega, np.interp(log.t, t, cols["omega"]), rtol=1e-7, atol=1e-6)
    assert np.max(np.abs(log.voltage - np.interp(log.t, t, v))) > 1.0  # (the steps' ramps, which it is not)
    assert any("voltage by its mean over each step" in n for n in log.notes)


def test_a_supplys_voltage_is_a_sample() -> None:
    """Told the voltage is a sample (a supply's), :func:`uniform` interpolates it like the sensors."""
    t = _jittered(100, 1e-2, 4)
    v = 16.0 + np.sin(t)
    _, ch, note = uniform(t, {"voltage": v}, resample=True, held=("command",))
    np.testing.assert_allclose(ch["voltage"], np.interp(t[0] + np.median(np.diff(t)) * np.arange(ch["voltage"].size),
                                                        t, v), rtol=1e-12)
    assert note is not None and "held" not in note


def test_a_slower_command_topic_merges_held() -> None:
    """Flight logs: an ESC topic at 100 Hz and its command topic at 40 Hz, each jittered; on the ESC's grid the
    command is its mean over each step (volt-seconds kept), the ESC's channels interpolated."""
    t_esc, t_cmd = _jittered(300, 1e-2, 5), _jittered(120, 2.5e-2, 6)
    u = np.repeat(np.random.default_rng(7).choice([0.1, 0.4, 0.8], 30), 4)
    grid, ch, notes = merge({"ESC": (t_esc, {"omega": 300.0 * np.cos(t_esc)}), "cmd": (t_cmd, {"command": u})},
                            "ESC", resample=True)
    np.testing.assert_allclose(ch["command"], _brute_mean(grid, t_cmd, u), atol=0.8 * 2 / 4000)
    np.testing.assert_allclose(ch["omega"], np.interp(grid, t_esc, 300.0 * np.cos(t_esc)), rtol=1e-12)
    assert "command by its mean over each step" in notes[0]
