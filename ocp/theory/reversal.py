"""Reversal theory of the seed paper as code: Lemma 1, Theorem 1, Corollary 1, Table I, the set S.

A regularity class is an integer level (:class:`Regularity`):

    UNBOUNDED (-2) < BOUNDED_DISCONTINUOUS (-1) < C^0 "continuous" (0) < C^1 (1) < ... < SMOOTH

Classes are derived, never typed in: a function that behaves near the crossing ``s = t - t_s`` like
the monomial ``c sign(s)^a |s|^e`` (:class:`Monomial`) has a regularity that follows from ``a`` and
``e`` exactly; time derivatives of monomials are monomials. The desired speed near a crossing of
order ``p`` (``x2d ~ alpha s^p``) is ``omega_d ~ sign(s)^p |s|^(p/2)``; torque/current follow the
class of ``omega_d'`` (eq. current_reference) and voltage that of ``omega_d''`` (eq.
voltage_reference). This reproduces Lemma 1 and, where the paper's Table I says "regular" or
"at least", gives the exact class (e.g. p = 4: the voltage is smooth, not only continuous).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from fractions import Fraction

import numpy as np

UNBOUNDED = -2
BOUNDED_DISCONTINUOUS = -1
CONTINUOUS = 0
SMOOTH = 10**6

Regularity = int


def regularity_label(level: Regularity) -> str:
    """``unbounded``, ``bounded-discontinuous``, ``continuous``, ``C1``, ``C2``, ..., ``smooth``."""
    if level == UNBOUNDED:
        return "unbounded"
    if level == BOUNDED_DISCONTINUOUS:
        return "bounded-discontinuous"
    if level == CONTINUOUS:
        return "continuous"
    if level >= SMOOTH:
        return "smooth"
    return f"C{level}"


def parse_regularity(label: str) -> Regularity:
    """Inverse of :func:`regularity_label`."""
    named = {"unbounded": UNBOUNDED, "bounded-discontinuous": BOUNDED_DISCONTINUOUS,
             "continuous": CONTINUOUS, "smooth": SMOOTH}
    if label in named:
        return named[label]
    if label.startswith("C") and label[1:].isdigit():
        return int(label[1:])
    raise ValueError(f"unknown regularity class {label!r}")


@dataclass(frozen=True)
class Monomial:
    """``sign(s)^a |s|^e`` near ``s = 0`` (the coefficient never changes the class).

    ``a`` matters only by parity; ``e`` is rational. ``dirac`` marks the derivative of a jump.
    """

    a: int
    e: Fraction
    dirac: bool = False

    def regularity(self) -> Regularity:
        if self.dirac or self.e < 0:
            return UNBOUNDED
        if self.e == 0:
            return BOUNDED_DISCONTINUOUS if self.a % 2 else SMOOTH
        if self.e.denominator != 1:
            return int(np.floor(float(self.e)))  # |s|^(k+1/2) is C^k, not C^(k+1)
        n = int(self.e)
        if (self.a + n) % 2 == 0:
            return SMOOTH  # sign(s)^a |s|^n = s^n
        return n - 1  # s^n sign(s) is C^(n-1), not C^n

    def derivative(self) -> Monomial:
        """d/ds; a jump (e = 0, a odd) differentiates into a Dirac; a constant into 0 (smooth)."""
        if self.dirac:
            return self
        if self.e == 0:
            if self.a % 2:
                return Monomial(self.a + 1, Fraction(0), dirac=True)
            return Monomial(0, Fraction(0))  # derivative of a constant: zero, smooth
        return Monomial(self.a + 1, self.e - 1)


# eq:Rm
def R_m(m: int) -> int:
    """Lemma 1 threshold: phi_r is C^m at 0 if r >= R_m (2m+4 for even m, 2m+3 for odd m)."""
    if m < 0:
        raise ValueError("m must be >= 0")
    return 2 * m + 4 if m % 2 == 0 else 2 * m + 3


def phi_monomial(r: int) -> Monomial:
    """The reversal monomial ``phi_r(s) = sign(s)^(r-2) |s|^((r-3)/2)`` of Lemma 1."""
    if r < 2:
        raise ValueError("r must be >= 2")
    return Monomial(r - 2, Fraction(r - 3, 2))


def lemma1(r: int) -> Regularity:
    """Regularity of ``phi_r`` at the origin (Lemma 1, exact)."""
    return phi_monomial(r).regularity()


def lemma1_sufficient(r: int, m: int) -> bool:
    """Lemma 1's sufficient condition for ``phi_r in C^m``: ``r >= R_m`` or ``r = 4q+1, q >= 1``."""
    return r >= R_m(m) or (r >= 5 and (r - 1) % 4 == 0)


def theorem_order(p: int) -> int:
    """Theorem order ``r = p + 1`` of a thrust zero of order ``p``."""
    return p + 1


def speed_monomial(p: int) -> Monomial:
    """``omega_d ~ sign(s)^p |s|^(p/2)`` for ``x2d ~ alpha s^p`` (static inverse, Fig. 1)."""
    if p < 1:
        raise ValueError("crossing order p must be >= 1")
    return Monomial(p, Fraction(p, 2))


@dataclass(frozen=True)
class CrossingClass:
    """Regularity of the ideal commands at a thrust zero of order ``p`` (``r = p + 1``)."""

    p: int
    r: int
    torque: Regularity
    current: Regularity
    voltage: Regularity

    @property
    def sign_change(self) -> bool:
        return self.p % 2 == 1

    def labels(self) -> dict[str, str | int]:
        return {"p": self.p, "r": self.r, "torque": regularity_label(self.torque),
                "current": regularity_label(self.current), "voltage": regularity_label(self.voltage)}


def crossing_class(p: int) -> CrossingClass:
    """Theorem 1 + Corollary 1 at one crossing: torque ~ current ~ omega_d', voltage ~ omega_d''."""
    w = speed_monomial(p)
    dw = w.derivative()
    # eq:current_reference: i_d = a1 w' + a2 w + a3 w|w|; w and w|w| = x2d are at least as regular as w'
    torque = min(dw.regularity(), w.regularity())
    # eq:voltage_reference: V_d = b1 w'' + ... ; Corollary 1: one derivative more than the current
    voltage = min(dw.derivative().regularity(), torque)
    return CrossingClass(p=p, r=theorem_order(p), torque=torque, current=torque, voltage=voltage)


def table_one(orders: tuple[int, ...] = (1, 2, 3, 4, 5, 7)) -> list[CrossingClass]:
    """Table I of the paper, regenerated from the lemma (rows for the given thrust orders p)."""
    return [crossing_class(p) for p in orders]


def sin_family_order(q: int) -> int:
    """Crossing order of ``A sin^(2q+1)(W t + phi)``: p = 2q + 1 at every zero (eq. sin_family)."""
    if q < 0:
        raise ValueError("q must be >= 0")
    return 2 * q + 1


def min_order_for(current: Regularity = UNBOUNDED, voltage: Regularity = UNBOUNDED,
                  sign_change: bool = True) -> int:
    """Smallest thrust order ``p`` whose ideal current/voltage are at least the given classes."""
    p = 1
    while True:
        c = crossing_class(p)
        if c.sign_change == sign_change and c.current >= current and c.voltage >= voltage:
            return p
        p += 1


def u_class(r: int) -> Regularity:
    """Theorem 1, item 4: regularity of the unique reproducing input at a crossing of order r."""
    return lemma1(r)


def r3_bound(y3: float) -> float:
    """Theorem 1, item 4(b): magnitude of the one-sided input limits at an r = 3 crossing."""
    return float(np.sqrt(abs(y3) / 2.0))


# eq:feasibility_set
def feasibility_bounds(ydot: np.ndarray, k: float, u_low: float, u_high: float) -> tuple[np.ndarray, np.ndarray]:
    """Boundary of S: for each ``y' != 0`` the admissible interval of ``y''``.

    From eq. inv_u, ``-u_low <= y''/(2 sqrt|y'|) + k y' <= u_high`` gives
    ``2 sqrt|y'| (-u_low - k y') <= y'' <= 2 sqrt|y'| (u_high - k y')``. Shapes follow ``ydot``.
    """
    yd = np.asarray(ydot, dtype=float)
    g = 2.0 * np.sqrt(np.abs(yd))
    return g * (-u_low - k * yd), g * (u_high - k * yd)


def in_feasibility_set(ydot: np.ndarray, yddot: np.ndarray, k: float, u_low: float, u_high: float) -> np.ndarray:
    """Boolean mask of points ``(y', y'')`` in S (points with ``y' = 0`` are never in S)."""
    lo, hi = feasibility_bounds(ydot, k, u_low, u_high)
    ydd = np.asarray(yddot, dtype=float)
    return (np.asarray(ydot) != 0) & (ydd >= lo) & (ydd <= hi)


class ReversalRegularity(StrEnum):
    """Command regularity a user asks for at each reversal (mission field ``regularity``)."""

    BOUNDED = "bounded"
    CONTINUOUS_CURRENT = "continuous-current"
    CONTINUOUS_VOLTAGE = "continuous-voltage"
    C1_VOLTAGE = "c1-voltage"

    def required(self, voltage_driven: bool = True) -> tuple[Regularity, Regularity]:
        """(current class, voltage class) required; a voltage-driven motor always needs bounded V."""
        v_min = BOUNDED_DISCONTINUOUS if voltage_driven else UNBOUNDED
        return {
            ReversalRegularity.BOUNDED: (BOUNDED_DISCONTINUOUS, v_min),
            ReversalRegularity.CONTINUOUS_CURRENT: (CONTINUOUS, v_min),
            ReversalRegularity.CONTINUOUS_VOLTAGE: (CONTINUOUS, CONTINUOUS),
            ReversalRegularity.C1_VOLTAGE: (CONTINUOUS, 1),
        }[self]


def min_sin_q(regularity: ReversalRegularity, voltage_driven: bool = True) -> int:
    """Smallest q of ``A sin^(2q+1)`` whose ideal commands meet ``regularity`` (eq. sin_family)."""
    cur, volt = regularity.required(voltage_driven)
    return (min_order_for(current=cur, voltage=volt, sign_change=True) - 1) // 2
