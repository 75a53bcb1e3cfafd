"""B-splines and their derivatives at many points at once, with scipy's arithmetic (issue 14: the answer's time).

An answer of the flat program evaluates its speed spline and two derivatives at ~10^4 times per phase set
(:class:`ocp.optimize.flat_solve.FlatPlan`); scipy's ``BSpline.__call__`` runs de Boor's recursion point by point
in C (~190 ns a point for degree 5 and its two derivatives here), once per phase and derivative. This module
runs the same recursion vectorised over the points (numpy, one pass for every phase and derivative order, ~2.7x
less time) and returns the same numbers bit for bit (the same IEEE operations in the same order):

* the interval ``ell`` of a point ``x`` with ``t[ell] <= x < t[ell + 1]`` (``k <= ell <= n - 1``, so a point at
  or beyond an end uses the end polynomial, as scipy's ``extrapolate=True``);
* the non-zero basis functions of degree ``j`` at ``x`` from those of degree ``j - 1`` (de Boor–Cox, scipy's
  ``_deBoor_D`` with no derivative): ``w = h[n-1] / (t[ell+n] - t[ell+n-j])``, ``h[n-1] += w (t[ell+n] - x)``,
  ``h[n] = w (x - t[ell+n-j])``;
* a spline's value ``0 + c[ell-k] B_0 + ... + c[ell] B_k`` (summed in that order).

The ``r``-th derivative, as scipy's ``BSpline.derivative`` builds it (``splder``: degree ``k - r`` on the knots
``t[r:-r]``), is a spline whose basis at ``x`` is level ``k - r`` of the same recursion, so one pass serves the
value and the derivatives. Knots: clamped or not, with distinct interior breakpoints ``t[k] < ... < t[n]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@dataclass(frozen=True)
class Knots:
    """A knot vector ``t`` (n + k + 1,) of degree ``k`` and its per-interval tables: ``nearby`` (2k, n - k) the
    knots ``t[ell + d]``, d = -(k-1)..k, of each interval ``ell = k..n-1``; ``gaps[j-1]`` (j, n - k) the
    denominators ``t[ell + m] - t[ell + m - j]``, m = 1..j, of level ``j`` of the recursion."""

    t: np.ndarray
    k: int
    nearby: np.ndarray
    gaps: tuple[np.ndarray, ...]

    @property
    def n(self) -> int:
        """Number of coefficients (basis functions)."""
        return int(self.t.size - self.k - 1)


@lru_cache(maxsize=32)
def _knots(key: bytes, k: int) -> Knots:
    t = np.frombuffer(key, dtype=np.float64).copy()
    n = t.size - k - 1
    if k < 1 or n <= k or not np.all(np.diff(t[k: n + 1]) > 0.0):
        raise ValueError("bspline: degree >= 1, more coefficients than the degree and distinct interior knots")
    ell = np.arange(k, n)
    nearby = t[ell[None, :] + np.arange(-(k - 1), k + 1)[:, None]]  # row d + k - 1: t[ell + d]
    gaps = tuple(np.array([nearby[m + k - 1] - nearby[m - j + k - 1] for m in range(1, j + 1)])
                 for j in range(1, k + 1))
    t.flags.writeable = nearby.flags.writeable = False
    return Knots(t=t, k=k, nearby=nearby, gaps=gaps)


def knots(t: np.ndarray, k: int) -> Knots:
    """The tables of the knot vector ``t`` (n + k + 1,) of degree ``k`` (cached per knot vector)."""
    return _knots(np.ascontiguousarray(t, dtype=np.float64).tobytes(), int(k))


def basis(kn: Knots, x: np.ndarray, lowest: int) -> tuple[np.ndarray, list[np.ndarray]]:
    """(``ell`` (M,) the interval of each point ``x`` (M,), the non-zero basis functions of degree ``k``,
    ``k - 1``, ..., ``lowest`` at ``x``: entry ``r`` shape (k - r + 1, M), row ``a`` the function ``ell - k + a``
    of the spline of degree ``k - r`` on the knots ``t[r:len(t)-r]``)."""
    k = kn.k
    x = np.asarray(x, dtype=np.float64)
    ell = np.searchsorted(kn.t, x, side="right") - 1
    np.clip(ell, k, kn.n - 1, out=ell)
    i = ell - k
    # a few work arrays written in place (out=): a new temporary per operation cost up to 5x more where the
    # allocator hands large blocks back to the system and takes them again (page faults on every use)
    near = kn.nearby.take(i, axis=1)
    right = np.subtract(near[k:], x, out=near[k:])  # row m - 1: t[ell + m] - x, m = 1..k
    left = np.subtract(x, near[:k], out=near[:k])  # row d + k - 1: x - t[ell + d], d = -(k-1)..0
    h = np.empty((k + 1, x.size))
    h[0] = 1.0
    w, up, down, gap = (np.empty((k, x.size)) for _ in range(4))
    levels = []
    for j in range(1, k + 1):
        kn.gaps[j - 1].take(i, axis=1, out=gap[:j])
        np.divide(h[:j], gap[:j], out=w[:j])  # w_m = h[m-1] / (t[ell+m] - t[ell+m-j]), m = 1..j
        np.multiply(w[:j], right[:j], out=up[:j])  # w_m (t[ell+m] - x): added to h[m-1]
        np.multiply(w[:j], left[k - j:], out=down[:j])  # w_m (x - t[ell+m-j]): h[m]
        np.add(0.0, up[0], out=h[0])
        np.add(down[: j - 1], up[1:j], out=h[1:j])
        h[j] = down[j - 1]
        if j >= lowest:
            levels.append(h[: j + 1].copy())
    return ell, levels[::-1]


def windows(coef: np.ndarray, k: int) -> np.ndarray:
    """Coefficients (P, n) of P splines (n: :attr:`Knots.n`; a derivative's fewer ones padded with zeros) as
    windows (k+1, P n): ``[a, p n + i]`` is ``coef[p, i + a]`` (zero past the end)."""
    P, n = coef.shape
    out = np.zeros((k + 1, P, n))
    for a in range(k + 1):
        out[a, :, : n - a] = coef[:, a:]
    return out.reshape(k + 1, P * n)


def combine(kn: Knots, ell: np.ndarray, funcs: np.ndarray, win: np.ndarray, which: np.ndarray | int) -> np.ndarray:
    """Values (M,) at the points of :func:`basis` (``ell`` (M,), ``funcs`` one of its entries) of spline
    ``which`` (M,) (or one index for every point) of the windows ``win`` (:func:`windows`), summed as scipy does:
    ``0 + c[ell-k] B_0 + c[ell-k+1] B_1 + ...``."""
    prod = win[: funcs.shape[0]].take(np.asarray(which) * kn.n + ell - kn.k, axis=1)
    prod *= funcs
    out = np.add(0.0, prod[0])
    for a in range(1, funcs.shape[0]):
        out += prod[a]
    return out
