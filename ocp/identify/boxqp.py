"""Bounded least squares on normal equations: ``min_x x'Gx - 2h'x`` subject to ``lo <= x <= hi`` (``G`` (P, P)
symmetric positive definite, P small), by a primal active set: the free variables solve their normal equations
with the bound ones held, a step that would leave the box stops at the first bound it meets (that variable is
held), and a held variable whose gradient points into the box is released. Each iteration is one P x P solve;
scipy's ``lsq_linear`` (BVLS) gives the same answer at ~1 ms of Python per call, and the model check fits thousands
of models per log.
"""

from __future__ import annotations

import numpy as np

#: a variable within this (relative to the box's scale) of a bound is on it
EDGE = 1e-12
#: rounds of holding every crossed bound at once before the one-at-a-time active set
FAST = 3


def box_qp(g: np.ndarray, h: np.ndarray, lo: np.ndarray, hi: np.ndarray, start: np.ndarray | None = None,
           max_iter: int = 0) -> np.ndarray:
    """The minimiser (P,) of ``x'Gx - 2h'x`` over the box ``[lo, hi]`` (P,) (entries may be infinite; ``lo <= hi``).
    ``start`` (P,): a first guess (e.g. the unconstrained minimiser), clipped to the box, each variable it puts on
    a bound held there at first (zeros if None); ``max_iter``: 0 for ``10 P + 10``; past it, the last feasible
    iterate."""
    p = h.size
    x = np.clip(np.zeros(p) if start is None else np.nan_to_num(start), lo, hi)
    held = (x <= lo) | (x >= hi)
    for _ in range(FAST):  # first, every bound the free solution crosses held at once (most fits end here)
        target = _free_solution(g, h, x, held)
        out = ~held & ((target < lo) | (target > hi))
        if not out.any():
            x = target
            if not _inward(g, h, x, lo, hi, held).any():
                return x
            break
        x, held = np.clip(target, lo, hi), held | out
    for _ in range(max_iter or 10 * p + 10):  # then one bound at a time (finite, descending)
        free = ~held
        target = _free_solution(g, h, x, held)
        step = target - x
        with np.errstate(divide="ignore", invalid="ignore"):
            room = np.where(step < 0, (lo - x) / step, np.where(step > 0, (hi - x) / step, np.inf))
        room = np.where(free, np.maximum(room, 0.0), np.inf)
        a = float(np.min(room)) if room.size else np.inf
        if a < 1.0:  # the step leaves the box: go to the first bound it meets and hold that variable
            k = int(np.argmin(room))
            x = np.clip(x + a * step, lo, hi)
            x[k] = lo[k] if step[k] < 0 else hi[k]
            held[k] = True
            continue
        x = target
        inward = _inward(g, h, x, lo, hi, held)
        if not inward.any():
            return x
        held[int(np.argmax(inward))] = False
    return x


def _free_solution(g: np.ndarray, h: np.ndarray, x: np.ndarray, held: np.ndarray) -> np.ndarray:
    """``x`` with its free variables minimising the objective, the ``held`` ones (P,) kept."""
    free = ~held
    target = x.copy()
    if free.any():
        target[free] = np.linalg.solve(g[free][:, free], h[free] - g[free][:, held] @ x[held])
    return target


def _inward(g: np.ndarray, h: np.ndarray, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
            held: np.ndarray) -> np.ndarray:
    """(P,) how strongly each held variable's descent points into the box (0: it stays on its bound). A variable
    boxed to a point (``hi - lo`` within :data:`EDGE`: a constant held at nominal beside its asymmetry, an empty
    column's ``[0, 1e-150]``) has no room: released, it stepped nowhere and was held again, and where its pull was
    the strongest the active set cycled on it to ``max_iter`` and never freed a variable that had to move
    (``tests/identify/test_box_qp.py``; a reverse-only log's fits took 10x the iterations)."""
    grad = g @ x - h  # (half the gradient)
    scale = np.abs(h) + np.abs(g).max(axis=1) * (np.abs(x) + 1.0)
    room = hi - lo > EDGE * (1.0 + np.minimum(np.abs(lo), np.abs(hi)))
    pull = np.where(room & (x <= lo), -grad, np.where(room & (x >= hi), grad, 0.0)) / scale
    return np.where(held & (pull > EDGE), pull, 0.0)
