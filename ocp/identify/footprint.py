"""Where a banded effect acts: the held-out rows on which its materiality is also judged.

A Stribeck band acts near zero speed only, a few per cent of a log's rows; the whole log's held-out score, which the
rows it cannot touch dilute, would hide a fall that is material where it acts (:func:`.evidence.is_material`,
:func:`.evidence.band_score`). :class:`Footprints` keeps, for each banded column of a design
(:class:`.regression.Design`), the held-out rows where it acts, and builds their Gram matrices per fold the first
time a model is scored there; the design's weighted columns themselves (:func:`weighted`), and the Gram matrices of
any sets of rows (:func:`grams`), the design's own.
"""

from __future__ import annotations

import numpy as np

from ocp import memory

#: effects whose columns act on a band of the rows only (a Stribeck band: near zero speed), their materiality also
#: judged on that band (:attr:`.regression.Design.footprint`, :func:`.evidence.is_material`)
BANDED = frozenset({"stribeck"})
#: a banded column acts on the rows where it reaches this share of its largest magnitude (weighted, after the view)
FOOTPRINT = 0.1


#: rows a Gram product copies out of the weighted columns at a time (:func:`grams`): the copy of a set of rows is
#: bounded (~80 MB at 100 columns) however long the log
ROWS_AT_ONCE = 1 << 15


def weighted(columns: list[np.ndarray], sigma: np.ndarray) -> np.ndarray:
    """The design's weighted columns ``a_all`` (3, Q, N), a column's rows contiguous: each of the Q ``columns``
    (3, N) divided by the equations' noise levels ``sigma`` (3,). The list is emptied as the array fills, each column
    dropped once written and the heap's free pages handed back every :data:`ocp.memory.GIVE_BACK_BYTES`, so that a
    long log's columns are not held twice (:mod:`ocp.memory`)."""
    a_all = np.empty((3, len(columns), columns[0].shape[1] if columns else 0))
    columns.reverse()
    dropped = 0
    for j in range(a_all.shape[1]):
        column = columns.pop()
        np.divide(column, sigma[:, None], out=a_all[:, j])
        dropped += column.nbytes
        del column
        if dropped >= memory.GIVE_BACK_BYTES:
            memory.give_back()
            dropped = 0
    return a_all


def grams(a_all: np.ndarray, tw: np.ndarray, rows: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per set of rows (K masks or index arrays over N): from the weighted columns ``a_all`` (3, Q, N) (a column's
    rows contiguous) and targets ``tw`` (3, N), the Gram matrices ``A'A`` (K, 3, Q, Q), ``A'r`` (K, 3, Q) and ``r'r``
    (K, 3) per equation, summed over pieces of at most :data:`ROWS_AT_ONCE` rows."""
    q = a_all.shape[1]
    g, h, c = np.zeros((len(rows), 3, q, q)), np.zeros((len(rows), 3, q)), np.zeros((len(rows), 3))
    for k, m in enumerate(rows):
        at_rows = np.flatnonzero(m) if m.dtype == bool else m
        for lo in range(0, at_rows.size, ROWS_AT_ONCE):  # (BLAS products, not einsum's loops: 17x faster)
            piece = at_rows[lo:lo + ROWS_AT_ONCE]
            at, t = a_all[:, :, piece], tw[:, piece]
            g[k] += at @ at.transpose(0, 2, 1)
            h[k] += (at @ t[:, :, None])[:, :, 0]
            c[k] += np.einsum("en,en->e", t, t)
    return 0.5 * (g + g.transpose(0, 1, 3, 2)), h, c  # (exactly symmetric, as the sums are)


class Footprints:
    """Where each banded column acts (:data:`FOOTPRINT` of its largest weighted magnitude in some equation) among
    the held-out rows, and, when first asked for a column (:meth:`grams`), the Gram matrices there per fold: only
    the bands a model picks are ever scored so (:func:`.evidence.band_score`). Holds the design's weighted columns
    (not a copy: the build's own arrays, alive as long as the design) and the indices of the rows where a band acts."""

    def __init__(self, a_all: np.ndarray, tw: np.ndarray, tests: list[np.ndarray], bands: list[int]) -> None:
        """``a_all`` (3, Q, N) weighted columns, ``tw`` (3, N) weighted targets, ``tests`` K held-out masks (N,)
        (disjoint: folds, or one split's held-out rows), ``bands`` the banded columns' indices."""
        held = np.full(a_all.shape[2], -1)
        for k, m in enumerate(tests):
            held[m] = k
        acts = {}
        for j in bands:
            mag = np.abs(a_all[:, j])
            top = mag.max(axis=1, keepdims=True)
            acts[j] = np.any((mag >= FOOTPRINT * top) & (top > 0), axis=0) & (held >= 0)
        rows = np.flatnonzero(np.any(list(acts.values()), axis=0)) if acts else np.zeros(0, dtype=int)
        self.folds = len(tests)
        self._a, self._t, self._rows, self._fold = a_all, tw, rows, held[rows]
        self._acts = {j: m[rows] for j, m in acts.items()}
        self._grams: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = {}

    def __contains__(self, j: object) -> bool:
        return j in self._acts

    def grams(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per fold, on the held-out rows where column ``j`` acts: ``g`` (K, 3, Q, Q), ``h`` (K, 3, Q), ``c`` (K, 3)
        and the row counts ``n`` (K, 3), as :attr:`.regression.Design.g_fold` etc."""
        if j not in self._grams:
            picks = [self._rows[self._acts[j] & (self._fold == k)] for k in range(self.folds)]
            counts = np.array([np.full(3, m.size) for m in picks]).reshape(-1, 3)
            self._grams[j] = (*grams(self._a, self._t, picks), counts)
        return self._grams[j]
