"""Angle-periodic torque (cogging, commutator ripple): its columns and its period count, in the angle domain.

A ripple ``tau_sin sin(n theta) + tau_cos cos(n theta)`` [N m] acts on the rotor through the angle, not time:
at speed ``w`` it is a tone at ``n |w| / (2 pi)`` Hz, often beyond a slow logger's Nyquist frequency, but the
angle is sampled too. Between two samples the angle moves (nearly) linearly, so the ripple's mean over a
row is known in closed form (:func:`interval_ripple`): on slow rows it is the ripple itself, on fast rows
it averages out (a sinc), never aliasing. The period count (1..64) is the one whose columns, fitted beside the
other columns, best predict the torque equation's held-out rows (:func:`ocp.identify.regression.build`);
:func:`angle_limits` says how much of the log can show a ripple of that count, and when it cannot. An angle
integrated from a speed column drifts as a random walk: there the ripple's phase may also be tracked between
knots (:func:`drift_windows`, :func:`track_phase`), its amplitude one over the log.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from ocp.logs import Log

MAX_PERIODS = 64
#: an angle integrated from a speed column drifts as a random walk; its ripple's phase is taken as known within
#: this variance [rad^2] between two knots of :func:`drift_windows` (a coherence of exp(-0.25) = 0.78 there)
DRIFT_VAR = 0.5
#: ... knots never closer than this [s] (the held-out segments must lie between knots fitted on training rows)
DRIFT_SPAN = 1.0
MAX_PIECES = 12


def rotor_angle(log: Log) -> np.ndarray:
    """The rotor angle (N,) [rad]: the logged one, else the speed column integrated by the trapezoid rule from 0."""
    if log.theta is not None:
        return log.theta
    return np.concatenate([[0.0], np.cumsum(0.5 * (log.omega[1:] + log.omega[:-1]) * log.dt)])


def _means(ea: np.ndarray, ed: np.ndarray, d: np.ndarray, triangle: bool) -> np.ndarray:
    """Row means (complex, (M,)) of ``exp(i phi)`` with the phase moving linearly from ``a`` by ``d`` over each
    interval (``ea = exp(i a)``, ``ed = exp(i d)``): ``int_0^1 exp(i (a + d u)) du`` (box), or the triangle
    over the interval before and this one, ``int_0^1 u ...`` rising then ``int_0^1 (1 - u) ...`` falling."""
    tiny = np.abs(d) < 1e-3
    safe = np.where(tiny, 1.0, d)
    box = ea * np.where(tiny, 1.0 + 0.5j * d - d * d / 6.0, (ed - 1.0) / (1j * safe))
    if not triangle:
        return np.asarray(box)
    up = ea * np.where(tiny, 0.5 + 1j * d / 3.0 - d * d / 8.0, ed / (1j * safe) + (ed - 1.0) / (safe * safe))
    prev = np.concatenate([up[:1], up[:-1]])  # the rising half over k-1 -> k (first row: its own interval)
    return np.asarray(prev + box - up)


def interval_ripple(theta: np.ndarray, n: int, triangle: bool) -> tuple[np.ndarray, np.ndarray]:
    """Weighted means of ``sin(n theta)`` and ``cos(n theta)`` (M,) on the rows of the sampled angle
    ``theta`` (M + 1,) [rad], moving linearly between samples: over each interval k -> k+1, or (``triangle``,
    :func:`ocp.identify.columns.raw_signals`) under the triangle over k-1 -> k+1. Integrated in closed
    form: a ripple faster than the sampling averages out (its impulse over the row, eq. dc_mechanical)
    instead of aliasing as samples at the instants would."""
    d = n * np.diff(theta)
    z = _means(np.exp(1j * n * theta[:-1]), np.exp(1j * d), d, triangle)
    return z.imag, z.real


def drift_windows(t: np.ndarray, periods: int, sigma_w: float, dt: float) -> np.ndarray:
    """Hat functions (M, K) over the row times ``t`` (M,) [s] for a ripple whose phase drifts: the angle integrated
    from a speed with white noise ``sigma_w`` [rad/s] per sample of ``dt`` [s] wanders as a random walk, the
    ripple's phase by ``n^2 sigma_w^2 dt`` [rad^2/s]; knots are spaced so that it wanders by :data:`DRIFT_VAR`
    between them (at least :data:`DRIFT_SPAN` apart, at most :data:`MAX_PIECES` pieces), the ripple's complex
    amplitude linear between knots. K = 1 (ones: one phase) where the whole log is within that variance."""
    span = _span(t)
    rate = periods * periods * sigma_w * sigma_w * dt
    pieces = min(_most_pieces(span), math.ceil(rate * span / DRIFT_VAR))
    if rate * span <= DRIFT_VAR or pieces < 1:
        return np.ones((t.size, 1))
    knots = np.linspace(t[0], t[-1], pieces + 1)  # (built (K, M): each hat contiguous, as the speed view filters it)
    return np.clip(1.0 - np.abs(knots[:, None] - t[None, :]) / (knots[1] - knots[0]), 0.0, None).T


def _span(t: np.ndarray) -> float:
    return float(t[-1] - t[0]) if t.size > 1 else 0.0


def _most_pieces(span: float) -> int:
    """Most pieces :func:`drift_windows` cuts ``span`` [s] into: knots at least :data:`DRIFT_SPAN` apart, at most
    :data:`MAX_PIECES` pieces (0: shorter than one span, one phase over the log)."""
    return min(MAX_PIECES, int(span / DRIFT_SPAN))


def tracked_periods(t: np.ndarray, sigma_w: float, dt: float) -> int:
    """The largest period count (0..64) whose phase :func:`drift_windows` can follow along an angle integrated from
    a speed with white noise ``sigma_w`` [rad/s] per sample of ``dt`` [s] over the row times ``t`` (M,) [s]: the
    random walk of a count ``n``'s phase between the closest knots allowed (at least :data:`DRIFT_SPAN` apart, at
    most :data:`MAX_PIECES` pieces; the whole log where it is shorter), ``n^2 sigma_w^2 dt spacing`` [rad^2], within
    :data:`DRIFT_VAR`. Beyond it the phase wanders between knots by more than the tracking assumes: a true count's
    tracked fit may then predict held-out rows no better than a wrong one's (proving-ground seed 23112, a tachometer
    at 1 kHz: 10 periods found at 34, the true count's held-out share 0.18 against 0.83; with the rig's own angle,
    0.999 at 10)."""
    span = _span(t)
    spacing = span / max(1, _most_pieces(span))
    per_count = sigma_w * sigma_w * dt * spacing
    return MAX_PERIODS if per_count <= 0 else int(min(MAX_PERIODS, math.sqrt(DRIFT_VAR / per_count)))


def track_phase(z: np.ndarray, h: np.ndarray, resid: np.ndarray, train: np.ndarray,
                view: Callable[[np.ndarray], np.ndarray] | None = None) -> np.ndarray:
    """Unit phasors (M,) that turn a ripple ``z`` (M,) (complex: cos + i sin of its row means) to follow a
    drifting angle: its complex amplitude fitted to ``resid`` (M,) on the ``train`` rows as K hat functions ``h``
    (M, K) (:func:`drift_windows`; columns through ``view`` as the residual), interpolated between knots and
    normalised. The ripple ``z w / |w|`` then has ONE amplitude over the log (a ripple's size does not drift,
    its phase does): a window fitted to noise turns the phase, it cannot add amplitude; knots are fitted on
    training rows only, so the held-out rows between them judge the tracking."""
    k = h.shape[1]
    a = np.empty((2 * k, h.shape[0])).T  # (M, 2K), each column contiguous (the view filters along them)
    np.multiply(z.imag[:, None], h, out=a[:, :k])
    np.multiply(z.real[:, None], h, out=a[:, k:])
    a = view(a) if view is not None else a  # (one call over all columns: rows first)
    at = a[train]
    x = np.linalg.lstsq(at.T @ at, at.T @ resid[train], rcond=1e-12)[0]  # (normal equations: 2K columns, many rows)
    w = h @ (x[k:] - 1j * x[:k])  # Re[w z] = c Re z + s Im z, per knot
    return np.asarray(w / np.maximum(np.abs(w), 1e-300))


def ripple_independence(theta: np.ndarray, periods: int, floor: float, cap: float) -> float:
    """Fraction of independent rows (0..1) of a ripple of ``periods`` per revolution of the angle ``theta``
    (M + 1,) [rad] against a residual that decorrelates over ``1 / floor`` rows: a row's ripple moves by
    ``n |dtheta| / (2 pi)`` periods and decorrelates over half a period, so a chance correlation with a slower
    residual averages over that many independent pieces per row, at most ``cap`` (the rows' own low-pass),
    at least ``floor`` (where the rotor stands still, the ripple is as slow as the residual). Mean over rows."""
    step = np.abs(np.diff(theta)) * periods / math.pi
    return float(np.mean(np.clip(step, floor, max(cap, floor)))) if step.size else floor


def angle_limits(theta: np.ndarray | None, periods: int, logged: bool, tracked: int = MAX_PERIODS
                 ) -> dict[str, object]:
    """What a log whose rotor angle is ``theta`` (N,) [rad] can show of a ripple of ``periods`` per
    revolution: the fraction of rows on which it
    is sampled at least twice per period (``n |dtheta| < pi``; on faster rows it averages out within a
    sample, :func:`interval_ripple`), the largest count resolved on half the moving rows, the largest count
    whose phase an integrated angle's drift lets the tracking follow (``tracked``, :func:`tracked_periods`), and a
    note when the log cannot show it (too few resolving rows, or an angle integrated from a speed column, whose
    drift blurs high counts) and when it resolves fewer counts than :data:`MAX_PERIODS` (the largest resolved one,
    and how much faster a logger must sample to resolve them all: over the proving ground's 800 logs, a drawn ripple
    beyond that count was named in about half the logs, within it in nearly all, ``bench/cogging_reach.py``)."""
    step = np.abs(np.diff(theta)) if theta is not None and theta.size > 1 else np.zeros(1)
    moving = step[step > 0]
    resolved = float(np.mean(periods * step < math.pi)) if step.size else 0.0
    top = int(min(MAX_PERIODS, math.pi / float(np.median(moving)))) if moving.size else MAX_PERIODS
    notes = []
    if resolved < 0.05:
        notes.append(f"at {periods} periods/rev the ripple is faster than half the sampling on "
                     f"{100 * (1 - resolved):.0f} % of the rows: this log cannot show it (a faster logger would)")
    if top < MAX_PERIODS:
        faster = MAX_PERIODS * float(np.median(moving)) / math.pi
        notes.append(f"a ripple of more than {top} periods/rev averages out within a sample on over half the moving "
                     f"rows and shows only where the rotor turns slowly, so it may go unseen (logging {faster:.2g} "
                     f"times faster, or a slower run, would resolve up to {MAX_PERIODS} on half the rows)")
    if not logged:
        notes.append("no angle column: the angle is integrated from the speed, whose noise makes it drift; "
                     + (f"its phase is followed up to {tracked} periods/rev only" if tracked < MAX_PERIODS else
                        "high period counts may not show") + " (log the encoder angle)")
    return {"rows_resolved": resolved, "max_resolved_periods": top, "angle": "logged" if logged else "integrated",
            "max_tracked_periods": tracked, "note": "; ".join(notes)}
