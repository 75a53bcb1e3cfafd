"""Analytic thrust references of the seed paper and their exact motor commands.

* :class:`SinProfile` -- ``x2d = A sin^(2q+1)(W t + phi)`` (eq. sin_family), thrust order p = 2q+1;
* :class:`LocalReversal` -- ``alpha (t - t_s)^p chi(t)`` blended smoothly into constant levels
  before and after the reversal (Section IV-A, "practical reference generation").

:func:`reference` turns either into a :class:`~ocp.reference.trajectory.Reference`: speed by the static inverse,
``omega_d``, ``omega_d'``, ``omega_d''`` by the chain rule on closed-form thrust derivatives, current
and voltage by eqs. current_reference / voltage_reference. Samples that fall on a crossing get the
right-hand limit (t -> t_s+) from the crossing's leading monomial: 0, a finite value, or +-inf with
the channel flagged unbounded (Theorem 1 / Corollary 1 decide, see :mod:`ocp.theory.reversal`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import cumulative_simpson
from scipy.special import beta, betainc

from ocp.errors import MissionError
from ocp.model.params import MotorParams
from ocp.reference.trajectory import Reference
from ocp.theory.reversal import UNBOUNDED, crossing_class, sin_family_order

_SNAP = 8.0 * np.finfo(float).eps
#: bounds of a sine-power profile (beyond them the closed forms overflow or lose every digit of the angle)
MAX_AMPLITUDE = 1e6  # N
MIN_PERIOD, MAX_PERIOD = 1e-6, 1e6  # s
MAX_PHASE = 1e3  # rad


@dataclass(frozen=True)
class Crossing:
    """Thrust zero ``x2d ~ alpha (t - t_s)^p`` [alpha in N/s^p]."""

    t_s: float
    p: int
    alpha: float


@dataclass(frozen=True)
class SinProfile:
    """``F(t) = A sin^(2q+1)(2 pi t / T + phi)``; A [N], T [s], phi [rad], q >= 0."""

    amplitude: float
    period: float
    q: int
    phase: float = 0.0

    def __post_init__(self) -> None:
        if not (0 < abs(self.amplitude) <= MAX_AMPLITUDE):
            raise MissionError("amplitude", f"must be a non-zero thrust [N] of magnitude at most {MAX_AMPLITUDE:g}")
        if not (MIN_PERIOD <= self.period <= MAX_PERIOD):
            raise MissionError("period", f"must be a time [s] in [{MIN_PERIOD:g}, {MAX_PERIOD:g}]")
        if not (isinstance(self.q, int) and 0 <= self.q <= 20):
            raise MissionError("q", "must be an integer in 0..20")
        if not abs(self.phase) <= MAX_PHASE:
            raise MissionError("phase", f"must be an angle [rad] of magnitude at most {MAX_PHASE:g}")

    @property
    def p(self) -> int:
        return sin_family_order(self.q)

    @property
    def W(self) -> float:
        return 2.0 * math.pi / self.period

    def _angle(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        x = self.W * t + self.phase
        s, c = np.sin(x), np.cos(x)
        s = np.where(np.abs(s) <= _SNAP * np.maximum(1.0, np.abs(x)), 0.0, s)  # exact zeros at crossings
        return x, s, c

    # eq:sin_family
    def thrust(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F [N], F' [N/s], F'' [N/s^2]), each shape (N,)."""
        _, s, c = self._angle(t)
        n, A, W = self.p, self.amplitude, self.W
        f = A * s**n
        df = A * n * W * s ** (n - 1) * c
        ddf = A * n * W**2 * ((n - 1) * s ** (n - 2) * c * c - s**n) if n > 1 else -A * W**2 * s
        return f, df, ddf

    def crossings(self, t0: float, t1: float) -> list[Crossing]:
        """Zeros in [t0, t1]: ``W t + phi = k pi``; near each ``F ~ A ((-1)^k W s)^n``."""
        W = self.W
        k0, k1 = math.ceil((W * t0 + self.phase) / math.pi - 1e-12), math.floor((W * t1 + self.phase) / math.pi + 1e-12)
        return [Crossing(t_s=(k * math.pi - self.phase) / W, p=self.p,
                         alpha=self.amplitude * (-1.0) ** (k * self.p) * W**self.p) for k in range(k0, k1 + 1)]

    def theta(self, t: np.ndarray, c_f: float) -> np.ndarray:
        """Closed-form rotor angle [rad] from t[0]: integral of omega = sign(F) sqrt(|F|/c_f).

        ``int sign(sin x)|sin x|^m dx`` over a quarter period is half an incomplete beta function.
        """
        m = self.p / 2.0
        a, b = (m + 1.0) / 2.0, 0.5
        full = beta(a, b)  # integral of |sin|^m over [0, pi]

        def half(r: np.ndarray) -> np.ndarray:  # r in [0, pi]
            rr = np.minimum(r, math.pi - r)
            part = 0.5 * full * betainc(a, b, np.sin(rr) ** 2)
            return np.where(r <= math.pi / 2, part, full - part)

        def g(x: np.ndarray) -> np.ndarray:
            r = np.mod(x, 2.0 * math.pi)
            return np.where(r < math.pi, half(np.minimum(r, math.pi)), full - half(np.clip(r - math.pi, 0, math.pi)))

        kappa = math.copysign(math.sqrt(abs(self.amplitude) / c_f), self.amplitude)
        x = self.W * t + self.phase
        return kappa / self.W * (g(x) - g(x[:1]))


def _smooth_step(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """C-infinity step psi: 0 for x <= 0, 1 for x >= 1, with psi' and psi''; shapes of x."""

    def f(z: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zz = np.where(z > 1e-3, z, 1.0)
        e = np.where(z > 1e-3, np.exp(-1.0 / zz), 0.0)
        return e, e / zz**2, e * (1.0 / zz**4 - 2.0 / zz**3)

    g, g1, g2 = f(x)
    h, h1, h2 = f(1.0 - x)
    h1, h2 = -h1, h2  # d/dx f(1-x) = -f'(1-x)
    d, d1 = g + h, g1 + h1
    n = g1 * h - g * h1
    n1 = g2 * h - g * h2
    return g / d, n / d**2, n1 / d**2 - 2.0 * n * d1 / d**3


@dataclass(frozen=True)
class LocalReversal:
    """``F(t) = chi M + (1 - chi) F_side`` with ``M = alpha (t - t_s)^p``.

    ``chi = 1`` for ``|t - t_s| <= flat`` and falls smoothly to 0 over ``blend`` [s]; ``F_side`` is
    ``before`` [N] for t < t_s and ``after`` [N] for t > t_s. Signs must agree with ``M`` on each side
    so that ``t_s`` is the only zero.
    """

    t_s: float
    p: int
    alpha: float
    flat: float
    blend: float
    before: float
    after: float

    def __post_init__(self) -> None:
        if not (isinstance(self.p, int) and 1 <= self.p <= 40):
            raise MissionError("p", "must be an integer in 1..40")
        for name in ("t_s", "alpha", "flat", "blend", "before", "after"):
            if not math.isfinite(getattr(self, name)):
                raise MissionError(name, "must be finite")
        if self.flat <= 0 or self.blend <= 0:
            raise MissionError("flat" if self.flat <= 0 else "blend", "must be positive [s]")
        if self.alpha == 0 or self.before == 0 or self.after == 0:
            raise MissionError("alpha", "alpha, before and after must be non-zero")
        if np.sign(self.after) != np.sign(self.alpha):
            raise MissionError("after", "must have the sign of alpha (the thrust after t_s)")
        if np.sign(self.before) != np.sign(self.alpha) * (-1) ** self.p:
            raise MissionError("before", "must have the sign of alpha (-1)^p (the thrust before t_s)")

    @classmethod
    def between(cls, before: float, after: float, t_s: float, p: int, duration: float) -> LocalReversal:
        """Reversal from ``before`` to ``after`` [N] taking ``duration`` [s] (half flat, half blend)."""
        half = duration / 2.0
        alpha = after / half**p if half > 0 else math.nan
        return cls(t_s=t_s, p=p, alpha=alpha, flat=half / 2.0, blend=half / 2.0, before=before, after=after)

    def thrust(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F, F', F''), each shape (N,)."""
        s = t - self.t_s
        p, a = self.p, self.alpha
        m, m1 = a * s**p, a * p * s ** (p - 1)
        m2 = a * p * (p - 1) * s ** (p - 2) if p >= 2 else np.zeros_like(s)
        psi, psi1, psi2 = _smooth_step((np.abs(s) - self.flat) / self.blend)
        chi, chi1, chi2 = 1.0 - psi, -psi1 * np.sign(s) / self.blend, -psi2 / self.blend**2
        side = np.where(s < 0, self.before, self.after)
        f = chi * m + (1.0 - chi) * side
        df = chi1 * (m - side) + chi * m1
        ddf = chi2 * (m - side) + 2.0 * chi1 * m1 + chi * m2
        return f, df, ddf

    def crossings(self, t0: float, t1: float) -> list[Crossing]:
        return [Crossing(self.t_s, self.p, self.alpha)] if t0 <= self.t_s <= t1 else []


@dataclass(frozen=True)
class SinReversal:
    """One reversal of the ``sin^(2q+1)`` family between two hold levels (eq. sin_family, locally).

    ``F = after sin^n(pi s / (2 rise))`` for ``0 <= s <= rise`` and ``F = -before sin^n(pi s / (2 fall))``
    for ``-fall <= s < 0`` (``s = t - t_s``, ``n = 2q+1``), the levels outside. The joins are at the
    sine's peaks (F' = 0 there); on a sine between its peaks (``rise = fall`` = a quarter period,
    ``before = -after``) it is exactly ``A sin^(2q+1)``.
    """

    t_s: float
    q: int
    before: float
    after: float
    fall: float
    rise: float

    def __post_init__(self) -> None:
        if not (isinstance(self.q, int) and 0 <= self.q <= 20):
            raise MissionError("q", "must be an integer in 0..20")
        if self.fall <= 0 or self.rise <= 0 or not (math.isfinite(self.fall) and math.isfinite(self.rise)):
            raise MissionError("rise", "rise and fall must be finite positive times [s]")
        if self.before * self.after >= 0:
            raise MissionError("after", "a reversal needs levels of opposite signs")

    @property
    def p(self) -> int:
        return sin_family_order(self.q)

    def thrust(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F, F', F''), each shape (N,)."""
        s = np.asarray(t, float) - self.t_s
        right = s >= 0
        amp = np.where(right, self.after, -self.before)
        W = np.where(right, math.pi / (2 * self.rise), math.pi / (2 * self.fall))
        x = np.clip(W * s, -math.pi / 2, math.pi / 2)
        inside = np.abs(W * s) <= math.pi / 2  # the window includes its peaks
        n = self.p
        sn, cs = np.sin(x), np.cos(x)
        sn = np.where(np.abs(sn) <= _SNAP, 0.0, sn)
        f = amp * sn**n
        df = np.where(inside, amp * n * W * sn ** (n - 1) * cs, 0.0)
        curv = (n - 1) * sn ** (n - 2) * cs * cs - sn**n if n > 1 else -sn
        ddf = np.where(inside, amp * n * W**2 * curv, 0.0)
        return f, df, ddf

    def crossings(self, t0: float, t1: float) -> list[Crossing]:
        alpha = self.after * (math.pi / (2 * self.rise)) ** self.p  # right-hand coefficient
        return [Crossing(self.t_s, self.p, alpha)] if t0 <= self.t_s <= t1 else []


@dataclass(frozen=True)
class PiecewiseProfile:
    """Reversal pieces (:class:`LocalReversal`, :class:`SinReversal`) joined at hold levels.

    ``pieces[k]`` acts on ``[edges[k], edges[k+1]]``; each equals its side levels exactly outside its
    reversal window, so neighbouring pieces join where both hold the same level.
    """

    pieces: tuple[LocalReversal | SinReversal, ...]
    edges: tuple[float, ...]

    def thrust(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        out = [np.zeros_like(t) for _ in range(3)]
        k = np.clip(np.searchsorted(np.asarray(self.edges), t, side="right") - 1, 0, len(self.pieces) - 1)
        for j, piece in enumerate(self.pieces):
            sel = k == j
            if sel.any():
                for o, v in zip(out, piece.thrust(t[sel]), strict=True):
                    o[sel] = v
        return out[0], out[1], out[2]

    def crossings(self, t0: float, t1: float) -> list[Crossing]:
        return [c for piece in self.pieces for c in piece.crossings(t0, t1)]


def _crossing_limits(alpha: float, p: int, c_f: float) -> tuple[float, float, float]:
    """Right-hand limits of (omega, omega', omega'') at ``x2d ~ alpha s^p``.

    ``omega ~ c sign(s)^p |s|^(p/2)``, c = sign(alpha) sqrt(|alpha|/c_f); p = 2 has a jump in omega'
    whose derivative is a Dirac (reported +-inf in omega'').
    """
    c = math.copysign(math.sqrt(abs(alpha) / c_f), alpha)
    e = p / 2.0
    dw = c * e if p == 2 else (math.copysign(math.inf, c) if p == 1 else 0.0)
    if p in (1, 3):
        ddw = math.copysign(math.inf, c * e * (e - 1.0))
    elif p == 2:
        ddw = math.copysign(math.inf, c)
    elif p == 4:
        ddw = 2.0 * c
    else:
        ddw = 0.0
    return 0.0, dw, ddw


def reference(profile: Any, params: MotorParams, t: np.ndarray) -> Reference:
    """Exact feedforward of ``profile`` for ``params`` on the grid ``t`` (N,) [s].

    ``profile`` is a :class:`SinProfile`, a :class:`LocalReversal` or anything with their
    ``thrust(t)`` and ``crossings(t0, t1)`` methods (e.g. :class:`PiecewiseProfile`).
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or np.any(np.diff(t) <= 0) or not np.all(np.isfinite(t)):
        raise MissionError("t", "must be a strictly increasing finite grid of at least two samples")
    cf = params.c_f
    f, df, ddf = profile.thrust(t)
    zero = f == 0.0
    af = np.where(zero, 1.0, np.abs(f))
    # static inverse (Fig. 1) and its chain-rule derivatives
    w = np.sign(f) * np.sqrt(np.abs(f) / cf)
    dw = df / (2.0 * np.sqrt(cf * af))
    ddw = ddf / (2.0 * np.sqrt(cf * af)) - df**2 * np.sign(f) / (4.0 * math.sqrt(cf) * af**1.5)
    a1, a2, a3 = params.current_coefficients
    b1, b2, b3, b4, b5 = params.voltage_coefficients
    crossings = profile.crossings(float(t[0]), float(t[-1]))
    for cr in crossings:
        idx = zero & (np.abs(t - cr.t_s) <= 1e-9 * max(1.0, abs(cr.t_s)) + 1e-12)
        w[idx], dw[idx], ddw[idx] = _crossing_limits(cr.alpha, cr.p, cf)
    with np.errstate(invalid="ignore"):
        # eq:current_reference
        i = a1 * dw + a2 * w + a3 * w * np.abs(w)
        # eq:voltage_reference
        v = b1 * ddw + b2 * dw + b3 * w + b4 * w * np.abs(w) + b5 * np.abs(w) * dw
    v = np.where(np.isinf(ddw), ddw, v)  # the most singular term dominates (no inf - inf)
    i = np.where(np.isinf(dw), dw, i)
    classes = [crossing_class(c.p) for c in crossings]
    unbounded = {
        "thrust": False, "omega": False, "theta": False,
        "omega_dot": any(c.torque == UNBOUNDED for c in classes),
        "current": any(c.current == UNBOUNDED for c in classes),
        "omega_ddot": any(c.voltage == UNBOUNDED for c in classes),
        "voltage": any(c.voltage == UNBOUNDED for c in classes),
    }
    theta = profile.theta(t, cf) if isinstance(profile, SinProfile) else cumulative_simpson(w, x=t, initial=0.0)
    return Reference(t=t, thrust=f, omega=w, omega_dot=dw, omega_ddot=ddw, theta=theta, current=i, voltage=v,
                     unbounded=unbounded, crossing_times=tuple(c.t_s for c in crossings),
                     crossing_orders=tuple(c.p for c in crossings))


def time_grid(duration: float, rate: float, t0: float = 0.0) -> np.ndarray:
    """Uniform grid [s] of ``round(duration*rate)+1`` samples from ``t0``; shape (N,)."""
    if not (math.isfinite(duration) and duration > 0):
        raise MissionError("duration", "must be a finite positive time [s]")
    if not (math.isfinite(rate) and rate > 0):
        raise MissionError("rate", "must be a finite positive sampling rate [Hz]")
    n = round(duration * rate) + 1
    if n > 2_000_001:
        raise MissionError("rate", f"duration*rate gives {n} samples; at most 2,000,001")
    return t0 + np.arange(n) / rate
