"""Which grid column a shaped effect takes (:func:`.select.fit_model`), given each column's training cost.

A shaped effect (a Stribeck band's speed, a Coulomb friction's edge, a wake lag) has one column per grid value; the
best by training cost is mixed with the better of its grid neighbours. A second shape fixed per column
(:attr:`.columns.Column.form`: Stribeck friction decaying exponentially beside the catalogue's Gaussian, a dead
band's gap beside its shift, a brush contact's soft drop over a current width beside the quasi-static one) splits the
grid into runs that are not neighbours of each other, and the non-default run is preferred only by a margin.
"""

from __future__ import annotations

from ocp.identify.columns import Column

#: a second shape other than the catalogue's is taken only where its best column lowers the training cost by this
#: fraction below the best default one: the decay is weakly determined where few rows are slow, and the level at
#: zero speed is extrapolated by it (a Gaussian friction of 5.3 mN m on a stalling 100 Hz log, validation seed
#: 13077, fitted exponentially 3 % better at 16.7 mN m). Set from the costs of 14 logs: Gaussian truths 0-9 %
#: better fitted exponentially, slower decays (``exp(-|r|^0.6-0.9)``) 16-79 % once the other effects are in
SHAPE_PREFERENCE = 0.1


def preferred(costs: list[float], cols: list[Column]) -> int:
    """Index of the column of least training cost ``costs`` (one per column ``cols``), where that column's second
    shape is not the default (:attr:`.columns.Column.plain`) only if it costs under ``1 - SHAPE_PREFERENCE`` times
    the best default one."""
    best = min(range(len(costs)), key=costs.__getitem__)
    plain = [m for m, c in enumerate(cols) if c.plain]
    if cols[best].plain or not plain:
        return best
    fallback = min(plain, key=costs.__getitem__)
    return best if costs[best] < (1.0 - SHAPE_PREFERENCE) * costs[fallback] else fallback


def neighbours(k: int, cols: list[Column]) -> list[int]:
    """The grid neighbours of column ``k`` among ``cols`` (ordered by second shape, then shape): those next to it
    with the same second shape."""
    same = [m for m in (k - 1, k + 1) if 0 <= m < len(cols)]
    return [m for m in same if cols[m].form == cols[k].form or (cols[m].plain and cols[k].plain)]
