"""Zero crossings of sampled thrust profiles: where, how flat, and what Theorem 1 says about them.

A sampled profile has no exact order; near an isolated zero ``t_s`` we fit
``|F| ~ |alpha| |t - t_s|^g`` by least squares in log-log coordinates on a window of
``0.15 x`` the distance to the nearest extremum of ``|F|``, refining ``t_s`` within one sample.
``g`` is the *local exponent*: an integer ``p`` for Table I profiles, but any real ``g`` for
speed-space reversals (``F ~ s|s|`` has g = 2 and changes sign). :data:`ORDER_TOLERANCE` is the
stated accuracy on ``g`` for profiles with at least :data:`MIN_WINDOW_SAMPLES` samples in the
window (tested on the analytic families up to p = 9 at 1 kHz).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ocp.errors import MissionError
from ocp.theory.reversal import UNBOUNDED, Regularity, crossing_class, in_feasibility_set

ORDER_TOLERANCE = 0.2
MIN_WINDOW_SAMPLES = 8


@dataclass(frozen=True)
class CrossingEstimate:
    """One zero of a sampled profile.

    Attributes:
        t_s: crossing time [s]
        exponent: fitted local exponent g (``|F| ~ |s|^g``); nan when the window was too small
        p: the integer order when ``|g - round(g)| <= ORDER_TOLERANCE``, else None
        sign_change: True for a reversal, False for a touch of zero
        samples: samples used in the fit
    """

    t_s: float
    exponent: float
    p: int | None
    sign_change: bool
    samples: int

    @property
    def r(self) -> int | None:
        return None if self.p is None else self.p + 1


def find_zeros(t: np.ndarray, f: np.ndarray, zero_tol: float = 0.0) -> list[tuple[int, bool]]:
    """Indices ``k`` of isolated zeros with a sign-change flag.

    A zero is a sign change between two consecutive samples (it lies in ``[t[k], t[k+1]]``) or a run
    of samples with ``|f| <= zero_tol`` (reported at the run's middle; a reversal when the samples
    around the run have opposite signs, a touch of zero otherwise). Zeros at the grid ends are
    boundary conditions, not crossings, and are not reported.
    """
    small = np.abs(f) <= zero_tol
    n = f.size
    # a sign change between two consecutive samples that are not zero
    out = [(int(k), True) for k in np.flatnonzero(~small[:-1] & ~small[1:] & (f[:-1] * f[1:] < 0))]
    # runs of zero samples (a zero at a grid end is a boundary condition, not a crossing)
    edges = np.diff(np.concatenate([[0], small.astype(np.int8), [0]]))
    for a, b in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1, strict=True):
        if a > 0 and b + 1 < n:
            out.append((int(a + b) // 2, bool(np.sign(f[a - 1]) * np.sign(f[b + 1]) < 0)))
    return sorted(out)


def sign_change_times(t: np.ndarray, f: np.ndarray, zero_tol: float = 0.0) -> list[float]:
    """Times [s] where ``f`` (N,) on ``t`` (N,) changes sign strictly inside the grid: linear interpolation
    between two samples of opposite sign, the sample itself where the change passes through zero samples
    (:func:`find_zeros`)."""
    out = []
    for k, sign_change in find_zeros(t, f, zero_tol):
        if not sign_change:
            continue
        f0, f1 = f[k], f[min(k + 1, t.size - 1)]
        if abs(f0) <= zero_tol or f0 * f1 >= 0:
            out.append(float(t[k]))
        else:
            out.append(float(t[k] + (t[k + 1] - t[k]) * f0 / (f0 - f1)))
    return out


def _window(t: np.ndarray, f: np.ndarray, k: int) -> float:
    """0.15 x distance from t[k] to the nearest local maximum of |f| (or the grid end)."""
    a = np.abs(f)
    dist = []
    for step in (1, -1):
        j = k + (1 if step > 0 else 0)
        while 0 < j < a.size - 1 and not (a[j] >= a[j - 1] and a[j] >= a[j + 1]):
            j += step
        dist.append(abs(t[j] - t[k]))
    return 0.15 * max(min(dist), 0.0)


def local_exponent(t: np.ndarray, f: np.ndarray, k: int, sign_change: bool) -> CrossingEstimate:
    """Fit the local exponent of the zero near ``t[k]`` (see module doc)."""
    from scipy.optimize import minimize_scalar  # here: the server imports this module, scipy.optimize costs ~0.6 s

    h = _window(t, f, k)
    dt = float(np.min(np.diff(t)))
    lo, hi = (t[k], t[k + 1]) if sign_change and k + 1 < t.size else (t[k] - dt, t[k] + dt)

    def fit(ts: float) -> tuple[float, float, int]:
        s = np.abs(t - ts)
        m = (s > 0.5 * dt) & (s <= h) & (f != 0)
        if m.sum() < MIN_WINDOW_SAMPLES:
            return np.inf, np.nan, int(m.sum())
        x, y = np.log(s[m]), np.log(np.abs(f[m]))
        g, c = np.polyfit(x, y, 1)
        return float(np.sum((y - (g * x + c)) ** 2)), float(g), int(m.sum())

    res = minimize_scalar(lambda ts: fit(ts)[0], bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-6 * dt})
    ts = float(res.x)
    _, g, n = fit(ts)
    p = round(g) if np.isfinite(g) and abs(g - round(g)) <= ORDER_TOLERANCE and round(g) >= 1 else None
    return CrossingEstimate(t_s=ts, exponent=g, p=p, sign_change=sign_change, samples=n)


def estimate_crossings(t: np.ndarray, f: np.ndarray, zero_tol: float | None = None) -> list[CrossingEstimate]:
    """All isolated zeros of the sampled thrust ``f`` (N,) on ``t`` (N,) with their local exponents."""
    t = np.asarray(t, dtype=float)
    f = np.asarray(f, dtype=float)
    if t.shape != f.shape or t.ndim != 1 or t.size < 3:
        raise MissionError("profile", "t and thrust must be 1-D arrays of equal length >= 3")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
        raise MissionError("profile", "t and thrust must be finite")
    if np.any(np.diff(t) <= 0):
        raise MissionError("profile.t", "must be strictly increasing")
    tol = 1e-12 * float(np.max(np.abs(f))) if zero_tol is None else zero_tol
    return [local_exponent(t, f, k, sc) for k, sc in find_zeros(t, f, tol)]


@dataclass(frozen=True)
class ProfileClassification:
    """Theorem 1 applied to a sampled thrust profile.

    Attributes:
        crossings: estimates at each zero
        torque / current / voltage: worst regularity class over the crossings (SMOOTH-valued
            ``theory`` levels; UNBOUNDED if any crossing has an unknown order below 2)
        reproducible_bounded: every crossing has r >= 3 and, when input bounds are given, the
            profile stays in the feasibility set S away from the crossings
        feasible_fraction: share of non-crossing samples inside S (1.0 without bounds)
    """

    crossings: list[CrossingEstimate]
    torque: Regularity
    current: Regularity
    voltage: Regularity
    reproducible_bounded: bool
    feasible_fraction: float


def classify_profile(t: np.ndarray, thrust: np.ndarray, c_f: float, k: float | None = None,
                     u_low: float | None = None, u_high: float | None = None) -> ProfileClassification:
    """Classify a sampled desired thrust [N] (Theorem 1 items 3-4, Corollary 1).

    With ``k`` [1/rad] and the normalised input bounds ``u_low, u_high`` [rad/s^2] the profile is also
    checked against S (eq. feasibility_set) in the normalised coordinates ``y' = F / c_f``.
    """
    est = estimate_crossings(t, thrust)
    classes = []
    for e in est:
        if e.p is not None:
            classes.append(crossing_class(e.p))
        elif np.isfinite(e.exponent) and e.exponent >= 1:
            classes.append(crossing_class(int(np.floor(e.exponent))))  # conservative: round down
        else:
            classes.append(crossing_class(1))
    worst = {ch: min((getattr(c, ch) for c in classes), default=10**6) for ch in ("torque", "current", "voltage")}
    frac = 1.0
    if k is not None and u_low is not None and u_high is not None:
        yd = np.asarray(thrust, float) / c_f
        ydd = np.gradient(yd, np.asarray(t, float))
        away = yd != 0
        frac = float(np.mean(in_feasibility_set(yd[away], ydd[away], k, u_low, u_high))) if away.any() else 1.0
    reproducible = worst["torque"] > UNBOUNDED and frac == 1.0
    return ProfileClassification(crossings=est, torque=worst["torque"], current=worst["current"],
                                 voltage=worst["voltage"], reproducible_bounded=reproducible, feasible_fraction=frac)
