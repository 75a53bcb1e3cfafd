"""The regression's columns of the saturating voltage drops (:data:`.columns.DROPS`: brush contact, a driver's dead
band), eq. dc_electrical [V], formed on the command the drive holds over a row (:func:`drop_columns`), and the
widths a dead band's gap is offered at (:func:`gap_widths`).
"""

from __future__ import annotations

import numpy as np

from ocp.identify.align import cutoff_hz, shifted, smooth
from ocp.identify.columns import GRID, Column, Signals
from ocp.logs import Log
from ocp.model.params import MotorParams

#: a driver dead band's forms (:class:`ocp.model.effects.VoltageDeadband`'s ``gap``): shifted (a dead time, the
#: default) and a gap (a minimum pulse); with the first alone no gap of the blind rig (``bench/blind_check.py``) was
#: named, with both 3 of the 5 its command enters (:mod:`.shape_choice` prefers the first)
DEAD_BAND_FORMS = (0.0, 1.0)
#: a brush contact's soft form (:attr:`.columns.Column.form`; the quasi-static one has none): the catalogue's own
#: ``v_b tanh(i / i_eps)`` (:class:`ocp.model.effects.BrushDrop`) with its current width ``i_eps`` on a grid of
#: :data:`SOFT_WIDTHS` shares of the logged peak current (:func:`drop_columns`)
SOFT_CONTACT = 1.0
SOFT_WIDTHS = (0.003, 0.1, 8)
#: the smallest share of the rows a gap dead band's width is put above, and how many widths so (:func:`gap_widths`): a
#: gap's width is the blend of two neighbouring columns (:func:`.explain.effect_values`), and a step of 1.45 in the
#: share between them (12 widths on a ramp) fitted the blind rig's gaps 5-22 % narrow (401, 533; the latter then lost
#: to a brush drop), a step of 1.2 (24) within 2.3 % (401, 533, 534)
GAP_SHARE, GAP_WIDTHS = 0.005, 24
#: a command whose magnitude spreads by more than this (relative standard deviation) holds several levels
#: (:func:`_levels`); a PRBS's quantised two levels spread by 0
LEVEL_SPREAD = 0.05


def drop_columns(name: str, p: MotorParams, s: Signals, log: Log,
                 held: tuple[np.ndarray, float] | None = None) -> list[tuple[Column, np.ndarray]]:
    """A saturating voltage drop (:data:`.columns.DROPS`) per width [V] on a grid, (3, M) at unit amplitude, eq.
    dc_electrical. A driver dead band (no output below ``v_db``) drops ``clip(V, +-v_db)`` (the command's sign;
    the catalogue's smooth ``V - v_db tanh(V / v_db)`` is for the optimiser); brushes drop ``v_b`` against the
    current, and while ``|V - k_e w| < v_b`` no current flows and the drop is ``V - k_e w``:
    ``clip(V - k_e w, +-v_b)`` (quasi-static). The drop acts on the held command, before the low-pass the
    equations see: it is formed on the log's command and low-passed like it (clipped after the low-pass, a step of
    the command, a PRBS edge, passes through the band within a row, not over the low-pass's rise, and leaves a
    residual at every edge). ``held``: the log's command (N,) [V] before the alignment shifted it by that many
    samples: the dead band acts on each held level, before the shift mixes two of them in a row. A width no row
    falls inside is the drop's sign times its width: a brush width so is not offered. A contact's drop may also be
    soft (its film conducts a little below the drop): ``v_b tanh(i / i_eps)``, the catalogue's own form, is offered
    over current widths ``i_eps`` (:data:`SOFT_CONTACT`); the blind rig's contact, ``V_b tanh(i / i_b)`` with ``i_b``
    2 % of the stall current, was fitted better by a dead band than by the quasi-static drop (blind 20: armature
    equation 0.35 against 1.69 noise units; 0.35 with the soft form). Only on a command of several magnitudes
    (:func:`_levels`): on two levels the current takes a few levels too, a wide soft drop is partly a resistance, and a
    30 % command gain came out as ``R``, ``k`` and a soft drop (session 75; a gain is said as such there, :mod:`.gain`).
    A dead band's on a command of
    one magnitude (two levels, a PRBS) is a drive gain no selection may name, and is built as a rival only
    (:attr:`.columns.Column.rival`): the brush drop, offered, differs from it only on the rows where the current
    opposes the command, and where the two fit alike both are said (proving ground 14025: a 1.70 V band fitted as a
    3.66 V brush drop, with no alternative said). Over several magnitudes (steps to random levels) a gain scales with
    the level and the dead band does not (:func:`_levels`): there it is offered (before session 15 it was not, and a
    dead band on a steps log was named a brush drop, proving-ground tuning seeds 6043, 6069, 6076, 6155)."""
    v = log.voltage[:s.v.size] if s.dt > 0 else s.v
    x, lag = (held[0], held[1]) if held is not None and name == "voltage_deadband" and s.dt > 0 else (v, 0.0)
    if name == "brush_drop":
        x = v - p.k_e * s.w
    fc = cutoff_hz(log, p.J * p.R / (p.k_t * p.k_e)) if s.dt > 0 else 0.0
    z = np.zeros_like(s.w)
    key = "v_b" if name == "brush_drop" else "v_db"
    v_peak = float(np.max(np.abs(s.v))) or 1.0
    widths = np.geomspace(0.005 * v_peak, 0.3 * v_peak, GRID)
    rival = name == "voltage_deadband" and not _levels(x) and not np.any(np.abs(x) < widths[-1])  # (no row inside)
    cols = [(Column(name, key, b, rival=rival), np.vstack([z, _low(shifted(np.clip(x, -b, b) / b, lag)[:s.v.size],
                                                                  s.dt, fc), z]))
            for b in widths if rival or np.any(np.abs(x) < b) or (name == "voltage_deadband" and _levels(x))]
    if name == "brush_drop" and s.dt > 0 and _levels(v):  # the soft contact, on the logged current (low-passed)
        i = log.current[:s.v.size]
        lo, hi, k = SOFT_WIDTHS
        cols += [(Column(name, key, w, form=SOFT_CONTACT), np.vstack([z, _low(np.tanh(i / w), s.dt, fc), z]))
                 for w in np.geomspace(lo, hi, k) * (float(np.max(np.abs(i))) or 1.0)]
    gaps = [(b, np.abs(x) < b) for b in gap_widths(x, widths)] if name == "voltage_deadband" else []  # (inside: lost)
    return cols + [(Column(name, key, b, form=DEAD_BAND_FORMS[1]),
                    np.vstack([z, _low(shifted(np.where(m, x, 0.0) / b, lag)[:s.v.size], s.dt, fc), z]))
                   for b, m in gaps if m.any() and not m.all()]


def gap_widths(x: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Widths [V] (K,), ascending, at which a gap dead band is offered on the command ``x`` (M,) [V]: the shifted
    form's ``widths`` ((W,) ascending), and :data:`GAP_WIDTHS` more put where the rows are, each just above the
    magnitude under which a share of the rows falls, the shares geometric from :data:`GAP_SHARE` to the share under
    the largest width, none under the smallest. A gap's column ``x [|x| < b] / b`` changes only where ``b`` passes a
    logged magnitude; the geometric grid alone can bracket the band with a width no row is under and the next a third
    beyond it (blind rig 534: a 0.93 V gap under a ramp from 0.84 V, between widths of 0.74 and 1.07 V, named
    nothing; the free run with the gap fell from 2.8 to 1.4 noise units). The grid stays: with the row widths alone
    blind 180's gap (a 14-sample delay beside it, PI at 500 Hz) fell under the selection's materiality (10.1 %
    against 13.6 % with the grid's)."""
    a = np.sort(np.abs(x))
    first, last = GAP_SHARE * a.size, int(np.searchsorted(a, widths[-1]))  # (rows inside)
    if last <= first:
        return np.empty(0)
    at = a[np.ceil(np.geomspace(first, last, GAP_WIDTHS)).astype(int) - 1]
    b = np.nextafter(at, np.inf)  # (just above: that row and those under it inside)
    return np.union1d(widths, b[(b >= widths[0]) & (b <= widths[-1])])


def _levels(x: np.ndarray) -> bool:
    """Whether the magnitudes of ``x`` (M,) spread over more than one level (a relative standard deviation over
    :data:`LEVEL_SPREAD`): then ``sign(x)`` is no gain on ``x`` (:func:`drop_columns`)."""
    a = np.abs(x)
    return bool(np.std(a) > LEVEL_SPREAD * np.mean(a))


def _low(y: np.ndarray, dt: float, fc: float) -> np.ndarray:
    """``y`` (M,) low-passed as :func:`.columns.signals` low-passes the log's channels (on a sweep, ``dt`` = 0: as it
    is)."""
    return smooth(y, dt, fc) if dt > 0 else y
