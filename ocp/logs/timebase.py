"""Time bases: irregular timestamps are put on a uniform grid (and the answer says so) or refused
with a reason -- never integrated on a median step as if they were regular.

A log is *regular* when every step is within ``JITTER`` of the median step. Otherwise, without
gaps longer than ``MAX_GAP`` median steps, every sampled channel is linearly interpolated onto the
uniform grid ``t0 + k h`` (``h`` the median step); with such a gap the log is refused (split it there).
A held channel (``HELD``: a command, which the drive keeps from its row's time to the next row's) is
put on the grid as its mean over each grid step (:func:`held_mean`), the held value each new row
needs for the same volt-seconds; interpolated, a step between two rows would become a ramp.
Several topics sampled at different rates (flight logs) are merged the same way onto the grid of
the reference topic, over the span they all cover.

Known limit, said in the note (:func:`drift`): the median of jittered steps is off by about ``1.25 sigma / sqrt(n)``
of a step and the grid ``t0 + k h`` accumulates that error, so it runs off the rows of a long log (half a sample over
6,000 rows of 1 % jitter, up to 28 samples on the blind rig's long logs of 10-25 % jitter), and the interpolation
averages neighbouring samples by a fraction that sweeps along the log: the noise levels read from such a log come out
low (proving ground seeds 0..29, the load cell: 0.55-0.64 of its level at half a sample of drift and more, 0.83-1.03
under 0.2).
The grid fitted to the stamps removes it, but moved verdicts the identifier's thresholds were tuned on
(``docs/model-check-history.md``, session 76).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ocp.errors import LogError

JITTER = 0.01  # relative
MAX_GAP = 5.0  # median steps
#: a step this many median steps long or longer has rows missing (:func:`drift`): two stamps each up to 0.37 of a step
#: off their rows (the blind rig clips its jitter at 0.3) make a single step at most 1.74 steps long
DROPPED = 1.75
#: a grid drifting this many samples off the stamps or more is said in the resampling's note (module doc)
DRIFT_NOTE = 0.1
#: the channels held from one row to the next (the armature voltage the drive applies, an ESC's command); the
#: others are samples
HELD = ("voltage", "command")


def steps(t: np.ndarray, name: str = "t") -> tuple[float, float]:
    """(median step [s], largest relative deviation from it); errors when time does not increase."""
    d = np.diff(t)
    bad = np.flatnonzero(d <= 0)
    if bad.size:
        raise LogError(name, f"must be strictly increasing (row {int(bad[0]) + 1})")
    h = float(np.median(d))
    return h, float(np.max(np.abs(d - h)) / h)


def drift(t: np.ndarray, h: float) -> float:
    """How far the grid ``t[0] + h k`` runs off the rows of the time stamps ``t`` (M,) [s] at its worst [median steps
    ``h`` [s]]: against the least-squares line of the stamps over their row numbers (one per step, a step of
    :data:`DROPPED` median steps or more counting its missing rows) (module doc)."""
    d = np.diff(t) / h
    rows = np.concatenate([[0.0], np.cumsum(np.where(d >= DROPPED, np.rint(d), 1.0))])  # (M,)
    r, c = rows - rows.mean(), t - t.mean()
    slope = float(r @ c / (r @ r))
    return float(np.max(np.abs(t[0] + h * rows - (t.mean() + slope * r))) / h)


def _gap(t: np.ndarray, h: float, name: str) -> None:
    d = np.diff(t)
    k = int(np.argmax(d))
    if d[k] > MAX_GAP * h:
        raise LogError(name, f"gap of {d[k]:.4g} s at t = {t[k] - t[0]:.4g} s (the median step is {h:.3g} s); "
                             "split the log at the gap")


def held_mean(grid: np.ndarray, h: float, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N,) a held signal's mean over each step ``[g_k, g_k + h)`` of the uniform ``grid`` (N,) [s] of step ``h``
    [s]: ``v`` (M,) held from each time ``t`` (M,) [s] to the next (the last row's value beyond it), so the
    integral of the result, held on the grid, equals the signal's at every grid point (eq. ZOH: a drive's
    volt-seconds). Linear interpolation would ramp a step across the jittered rows around it; an armature
    settling within a row (L/R under a sample) shows the step where it was (blind rig 509, 744)."""
    dv = v - v[0]  # (about the first value: a constant command stays exactly constant)
    area = np.concatenate([[0.0], np.cumsum(dv[:-1] * np.diff(t))])  # (M,) its integral up to each row [unit s]
    edges = np.append(grid, grid[-1] + h)
    at = np.where(edges <= t[-1], np.interp(edges, t, area), area[-1] + dv[-1] * (edges - t[-1]))
    return v[0] + np.diff(at) / h


def _onto(grid: np.ndarray, h: float, t: np.ndarray, v: np.ndarray, held: bool) -> np.ndarray:
    """``v`` (M,) sampled at ``t`` (M,) [s] on the uniform ``grid`` (N,) of step ``h`` [s]: by its mean over each step
    where it is ``held`` (:func:`held_mean`), else interpolated."""
    return held_mean(grid, h, t, v) if held else np.interp(grid, t, v)


def _drift_note(samples: float) -> str:
    """The resampling note's clause for a grid ``samples`` [median steps] off the stamps at its worst (:func:`drift`;
    none under :data:`DRIFT_NOTE`)."""
    return (f"; the grid runs up to {samples:.2g} samples off the time stamps' own rows (the median step is off "
            "their clock's by a fraction that adds up over the rows), so the interpolation averages neighbouring "
            "samples and the noise levels read from them come out low" if samples >= DRIFT_NOTE else "")


def _held_note(kept: list[str]) -> str:
    """The resampling note's clause for the held channels ``kept`` (empty: none)."""
    return f", {', '.join(kept)} by its mean over each step (held between rows)" if kept else ""


def uniform(t: np.ndarray, channels: Mapping[str, np.ndarray], resample: bool,
            name: str = "t", held: tuple[str, ...] = HELD) -> tuple[np.ndarray, dict[str, np.ndarray], str | None]:
    """``(t, channels, note)`` on a uniform grid; ``note`` says what was done (None: already regular); the channels
    named in ``held`` as held signals (:func:`held_mean`), the others interpolated."""
    h, jitter = steps(t, name)
    if jitter <= JITTER:
        return t, dict(channels), None
    if not resample:
        raise LogError(name, f"irregular sample times (steps {np.min(np.diff(t)):.3g} to {np.max(np.diff(t)):.3g} s, "
                             f"median {h:.3g} s); allow resampling or resample to a uniform grid first")
    _gap(t, h, name)
    grid = t[0] + h * np.arange(int(np.floor((t[-1] - t[0]) / h + 1e-9)) + 1)
    out = {k: _onto(grid, h, t, v, k in held) for k, v in channels.items()}
    note = (f"{name}: irregular sample times (steps up to {100 * jitter:.0f} % off the median {h:.3g} s): "
            f"{t.size} samples resampled onto a uniform {h:.3g} s grid by linear interpolation ({grid.size} samples)"
            + _held_note([k for k in out if k in held]) + _drift_note(drift(t, h)))
    return grid, out, note


def merge(topics: Mapping[str, tuple[np.ndarray, Mapping[str, np.ndarray]]], reference: str,
          resample: bool, held: tuple[str, ...] = HELD) -> tuple[np.ndarray, dict[str, np.ndarray], list[str]]:
    """Channels of several topics ``{topic: (t (M_k,), {channel: (M_k,)})}`` on the uniform grid of ``reference``
    (those named in ``held`` as held signals, :func:`held_mean`).

    Returns ``(t (N,), {channel: (N,)}, notes)``; errors name the topic with a gap or no overlap.
    """
    t_ref, _ = topics[reference]
    h = steps(t_ref, reference)[0]
    lo = max(float(tk[0]) for tk, _ in topics.values())
    hi = min(float(tk[-1]) for tk, _ in topics.values())
    if hi - lo < 2 * h:
        raise LogError(reference, f"the topics {sorted(topics)} do not overlap in time")
    if len(topics) == 1:
        t, chans, note = uniform(t_ref, topics[reference][1], resample, reference, held)
        return t, chans, [note] if note else []
    if not resample:
        raise LogError(reference, "channels sampled at different times; allow resampling to merge them")
    for name, (tk, _) in topics.items():
        _gap(tk, float(np.median(np.diff(tk))), name)
    grid = lo + h * np.arange(int(np.floor((hi - lo) / h + 1e-9)) + 1)
    out: dict[str, np.ndarray] = {}
    for tk, tchans in topics.values():
        for c, v in tchans.items():
            out[c] = _onto(grid, h, tk, v, c in held)
    rates = ", ".join(f"{n} {1 / float(np.median(np.diff(tk))):.3g} Hz" for n, (tk, _) in topics.items())
    return grid, out, [f"topics ({rates}) resampled by linear interpolation onto the {h:.3g} s grid of "
                       f"{reference}, over the {hi - lo:.3g} s they all cover ({grid.size} samples)"
                       + _held_note([c for c in out if c in held])]
