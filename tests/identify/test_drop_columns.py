"""Saturating voltage drops (dead band, brush contact) formed on the held command, before the low-pass (issue #11).

A drop acts on the command the drive holds over a sample; the equations see the log low-passed. Clipped after the
low-pass (the former columns), a command step passed through the band over the filter's rise instead of within a
row and left a residual at every PRBS edge, which a second drop then explained: on proving-ground tuning draw 1082
(a 1.5 V dead band and a 5.4 ms input delay, PRBS and a ramp at 1 kHz; never the reported seeds 0..199) the dead
band alone left the armature equation at 1.35 noise units and a 0.34 V brush drop was named beside it. Formed on
the held levels (before the alignment's sub-sample shift mixes two of them) and low-passed like the command, the
dead band leaves it at the noise. A width no row of the command falls inside is not offered to the selection: on a
two-level command the drop is then a drive gain, and its columns are the brush drop's rival only
(tests/identify/test_drop_rival.py).
"""

from __future__ import annotations

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.columns import signals
from ocp.identify.drops import drop_columns, gap_widths
from ocp.logs import Log, log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams, preset
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _log(voltage: np.ndarray, dt: float = 1e-3) -> Log:
    """A log of ``voltage`` (N,) [V] with a current and a speed that follow it (first-order lags, SI)."""
    n = voltage.size
    t = dt * np.arange(n)
    w = np.zeros(n)
    for k in range(1, n):
        w[k] = w[k - 1] + (voltage[k - 1] * 10.0 - w[k - 1]) * 0.05
    return log_from_arrays(t, voltage, 0.1 * voltage, 1e-3 * w * np.abs(w), omega=w)


def test_dead_band_columns_need_rows_inside_the_band() -> None:
    p = preset("paper-rig")
    prbs = np.where((np.arange(2000) // 37) % 3 == 1, -6.0, 6.0)  # two levels: every width below 6 V saturates
    log = _log(prbs)
    rivals = drop_columns("voltage_deadband", p, signals(log, p), log)
    assert len(rivals) == 12 and all(c.rival for c, _ in rivals)  # (the shifted form at each width; no gap)
    few = prbs.copy()
    few[::500] = 1.0  # four rows inside the wider bands: still one magnitude (drops._levels), but some rows tell
    some = drop_columns("voltage_deadband", p, signals(_log(few), p), _log(few))
    assert some and not any(c.rival for c, _ in some)  # offered as before, at the widths rows fall inside only
    assert all(np.any(np.abs(few) < c.shape) for c, _ in some) and len({c.shape for c, _ in some}) < 12
    ramp = _log(np.linspace(-6.0, 6.0, 2000))  # passes through every band
    cols = drop_columns("voltage_deadband", p, signals(ramp, p), ramp)
    assert all(c.item == "voltage_deadband" and not c.rival for c, _ in cols)
    # both forms (drops.DEAD_BAND_FORMS): shifted at each of the 12 widths; a gap at those and at up to
    # drops.GAP_WIDTHS (24) more put where the rows are (drops.gap_widths), from 0.5 % of the rows inside to the share
    # under the largest shifted width (0.3 of the peak: 30 % of a ramp's rows)
    plain = sorted(c.shape for c, _ in cols if c.plain)
    gaps = [c.shape for c, _ in cols if not c.plain]
    assert len(plain) == 12 and {c.form for c, _ in cols if not c.plain} == {1.0} and set(plain) <= set(gaps)
    inside = [float(np.mean(np.abs(ramp.voltage) < b)) for b in sorted(set(gaps) - set(plain))]
    assert 16 <= len(inside) <= 24 and 0.004 <= min(inside) <= 0.01 and 0.25 <= max(inside) <= 0.3


def test_dead_band_column_is_the_low_passed_drop_of_the_held_command() -> None:
    p = preset("paper-rig")
    v = np.where((np.arange(2000) // 50) % 2 == 1, -6.0, 6.0)
    v[1000:1400] = np.linspace(-6.0, 6.0, 400)  # a ramp: rows inside the band
    log = _log(v)
    s = signals(log, p)
    for _, a in drop_columns("voltage_deadband", p, s, log):
        # linear in the drop: the column is what the low-pass makes of clip(V, +-w) / w, bounded by one
        # (clipped after the low-pass it would follow the low-passed command through the band at every edge)
        assert np.max(np.abs(a[1])) <= 1.0 + 0.1  # (a second-order Butterworth overshoots by ~4 %)
        assert np.all(a[0] == 0.0) and np.all(a[2] == 0.0)
        edge = np.flatnonzero(np.diff(np.sign(v[:-1])) != 0)[0]  # the first PRBS edge
        assert abs(a[1][edge]) < 0.9  # within the filter's rise, not already at the new level


def test_dead_band_beside_a_delay_is_not_also_a_brush_drop() -> None:
    case = make_case(1082)
    assert case.expected == {"input_delay", "voltage_deadband"}
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert sorted(res.verdict) == ["input_delay", "voltage_deadband"]
    band = next(e for r in res.rounds for e in r.entries if e.name == "voltage_deadband" and e.significant)
    assert abs(band.parameters["v_db"] / case.truth.e("voltage_deadband", "v_db") - 1.0) < 0.2


def test_dead_band_is_offered_over_several_magnitudes_none_inside() -> None:
    """Steps to several magnitudes, none inside any width offered (all above 0.3 of the peak): the dead band's
    column is the command's sign (no gain on it), offered at every width; a PRBS's one magnitude stays refused."""
    p = preset("paper-rig")
    levels = np.array([4.0, -6.0, 5.0, -4.5, 6.0, -5.5])
    v = np.repeat(levels, 400)
    log = _log(v)
    cols = drop_columns("voltage_deadband", p, signals(log, p), log)
    assert len(cols) == 12
    settled = np.concatenate([np.arange(k * 400 + 100, (k + 1) * 400 - 100) for k in range(levels.size)])
    for _, a in cols:  # closed form: sign(V) on the rows the low-pass has settled on
        np.testing.assert_allclose(a[1][settled], np.sign(v[settled]), atol=1e-6)
    assert drop_columns("brush_drop", p, signals(log, p), log) != []  # (brushes: rows inside, as before)


def test_a_dead_band_on_steps_is_not_named_a_brush_drop() -> None:
    """Proving-ground tuning draw 6155 (2 kHz, steps to random levels, a dead band alone): named a brush drop
    before session 15 (the dead band was not offered: no command row inside its band)."""
    case = make_case(6155)
    assert set(case.truth.effects) == {"voltage_deadband"} and not case.constant_error  # (the premise)
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert res.verdict == ["voltage_deadband"]
    fitted = res.ranking[0].parameters["v_db"]
    assert fitted == pytest.approx(case.truth.e("voltage_deadband", "v_db"), rel=0.05)


def test_gap_widths_sit_just_above_logged_magnitudes_where_the_rows_are() -> None:
    """A ramp from 0.84 to 7.5 V that never reverses (as the blind rig's 534): the shifted form's geometric widths
    have none between 0.74 V (no row under it) and 1.07 V (a third of its rows beyond a 0.93 V band); the gap's widths
    added to them are each the next float above a logged magnitude, with rows under them in a geometric progression
    (0.5 % of the rows to the share under the largest width, 24 steps), so one is within 2 % of that band."""
    x = np.linspace(0.84, 7.5, 16000)
    widths = np.geomspace(0.005 * 7.5, 0.3 * 7.5, 12)
    got = gap_widths(x, widths)
    assert np.all(np.diff(got) > 0) and set(widths) <= set(got)  # (the grid's widths kept)
    b = np.setdiff1d(got, widths)
    assert np.all(np.isin(np.nextafter(b, -np.inf), x))
    inside = np.array([np.sum(x < w) for w in b])
    ratio = inside[1:] / inside[:-1]
    assert b.size == 24 and inside[0] == 80 and inside[-1] == np.sum(x < widths[-1])
    np.testing.assert_allclose(ratio, ratio[0], rtol=0.1)  # (geometric, to a row's rounding)
    assert np.min(np.abs(b / 0.93 - 1.0)) < 0.02
    assert not any(0.84 < w < 1.068 for w in widths)  # (the premise)
