"""Competing explanations on held-out evidence, over the Gram matrices of :mod:`.regression`.

A *model* is a set of items: catalogue effects and named constants. Fitting it is a bounded linear
least-squares problem on the training rows: every constant is always refined (that is calibration),
within ``+-tolerance`` of nominal unless the model *names* it (then within -80 % .. +300 %); effects
in the model get their columns (the best shape on a grid by training cost, mixed with a grid neighbour),
sign-bounded as the catalogue's lower bounds say; effects outside it are zero. A constant the log cannot resolve
(:attr:`.regression.Design.unresolved`, e.g. ``L`` under a current filter) is a free nuisance (-80 % .. any):
boxed in, what it stands for would be explained by a wrong item (brush drop, dead band, ``R``).
Its score is the held-out RMS of the three
weighted equation residuals, ``sqrt(mean_e MS_e / sigma_e^2)`` (about 1 for a model at the noise).

Forward selection adopts, while some equation's held-out RMS is above ``noise_floor``, the best-scoring item
that enters such an equation (:func:`_room`: one at its noise has nothing left for an item acting there alone)
and whose win passes its test (the tests differ by item, so the best-scoring one may fail where the next passes):
the score falls beyond sampling noise (the pooled score's scatter, or one equation's
own: :func:`_beyond_scatter`) -- for an effect also by at least ``min_improvement`` (its materiality, on the
score with every equation the effect does not enter counted at most at its noise level: :func:`_material`); a
constant's materiality is the tolerance itself (calibration already takes the first ``tol`` of its error, and
beyond it the user wants the name), so a constant freed beyond it needs only to win beyond sampling noise --
or, the models being nested and scored on the same rows, in a paired comparison over held-out blocks
(:func:`_blocks_agree`). After the forward rounds, each adopted constant, then each effect but the last one adopted,
is tested again beside all the other adopted items, and dropped (a constant: calibrated, not named) where it no longer
wins: a greedy first pick that stood for a mix of the items adopted after it (a thrust asymmetry taken first for a
wake lag and a force offset) leaves nothing of its own once they are in.
Where no item clears that alone, two that clear it only together (and each against the other alone) are adopted
as a pair (:func:`_pair`).
A constant that would have to be off by more than :data:`IMPLAUSIBLE_FACTOR` yields to an effect that fits as
well (a prior on constant errors: :func:`_prefer_effects`). Then every adopted item is challenged: an
alternative that swaps it for another item and scores within ``ambiguity_margin`` makes the verdict
``ambiguous`` (both candidates and the reason are reported) instead of a confident wrong name.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from scipy.optimize import lsq_linear

from ocp.identify.regression import CONSTANTS, NUISANCES, Design
from ocp.model.effects import CATALOGUE

NAMED_BOUNDS = (-0.8, 3.0)
#: a constant off by more than this factor (either way) is a less likely error than a missing effect that fits
#: the held-out data as well: the prior on constant errors behind :func:`_prefer_effects`
IMPLAUSIBLE_FACTOR = 2.0
#: a pair of items is tried among this many best single challengers when none clears the test alone (:func:`_pair`)
PAIR_TOP = 4
#: effects whose columns are a saturation ``clip(x, +-w) / w`` (a driver dead band, a brush drop: no output or no
#: current inside the band): physically the drop saturates at the band's width, so a column's amplitude is its
#: width, within this factor (a grid step, ~1.45, and the calibration of the constants); a 0.3 V "dead band" of
#: 1.4 V width is no dead band (it would explain a brush drop by a reduced gain at low voltage)
SATURATING = frozenset({"brush_drop", "voltage_deadband"})
SATURATION_SLACK = 1.5
#: the paired block test of a constant (:func:`_blocks_agree`): one-sided level, and the fewest held-out blocks
BLOCK_ALPHA = 0.01
BLOCK_MIN = 4
#: ... and the fall of that equation's held-out RMS it needs (the tolerance's own 10 %: a constant's materiality)
BLOCK_FALL = 0.10


@dataclass(frozen=True)
class Fitted:
    """A model fitted on training rows: its items, chosen columns, coefficients, training cost, held-out score."""

    items: tuple[str, ...]
    cols: tuple[int, ...]
    x: np.ndarray
    train_cost: float
    score: float
    per_eq: np.ndarray  # held-out RMS per equation [sigma units], (3,)

    def coefficient(self, j: int) -> float:
        return float(self.x[self.cols.index(j)]) if j in self.cols else 0.0


def _bounds(design: Design, cols: Sequence[int], named: set[str], tol: float,
            above: dict[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = [], []
    above = design.above if above is None else above
    for j in cols:
        c = design.columns[j]
        if c.item in NUISANCES:
            a, b = -1.0, np.inf  # a sensor lag; a lead of up to one sample: a current settling within a sample
        elif c.item in CONSTANTS:
            # a constant the log cannot resolve is a free nuisance (never named): boxing it in would leave
            # what it stands for (a current filter for L) to be explained by a wrong item
            box = tol + design.slack.get(c.item, 0.0)  # (wider where a nuisance could mimic the error)
            a, b = (NAMED_BOUNDS[0], np.inf) if c.item in design.unresolved else \
                NAMED_BOUNDS if c.item in named else (-box, box + above.get(c.item, 0.0))
        elif c.item in SATURATING:  # the drop saturates at its width: amplitude = width (module doc)
            a, b = c.shape / SATURATION_SLACK, c.shape * SATURATION_SLACK
        else:
            a, b = (0.0 if CATALOGUE[c.item].bounds.get(c.key, (-1.0, 1.0))[0] >= 0 else -np.inf), np.inf
        lo.append(a)
        hi.append(b)
    return np.array(lo), np.array(hi)


def solve(design: Design, cols: Sequence[int], named: set[str], tol: float,
          above: dict[str, float] | None = None) -> Fitted:
    """Bounded least squares on the training Gram matrices (``min x'Gx - 2h'x``) of columns ``cols`` (``above``:
    the boxes' widening above nominal, :attr:`.regression.Design.above` when None)."""
    idx = np.array(cols, dtype=int)
    g = design.g_train.sum(axis=0)[np.ix_(idx, idx)]
    h = design.h_train.sum(axis=0)[idx]
    d = np.sqrt(np.maximum(np.diag(g), 1e-300))
    gs = g / np.outer(d, d) + 1e-10 * np.eye(idx.size)
    lo, hi = _bounds(design, cols, named, tol, above)
    try:
        r = np.linalg.cholesky(gs).T
    except np.linalg.LinAlgError:
        r = np.linalg.cholesky(gs + 1e-6 * np.eye(idx.size)).T
    y = np.linalg.solve(gs, h / d)  # unconstrained first; bounded only when a bound binds
    if not np.all(np.isfinite(y)) or np.any(y < lo * d) or np.any(y > hi * d):  # (near-singular: bounded too)
        y = lsq_linear(r, np.linalg.solve(r.T, h / d), bounds=(lo * d, hi * d), method="bvls").x
    x = np.where(d > 1e-9 * d.max(), y / d, 0.0)  # a column the log leaves empty (L far under a sample): 0
    cost = float(design.c_train.sum() - 2 * h @ x + x @ g @ x)
    ms = np.array([(design.c_test[e] - 2 * design.h_test[e][idx] @ x + x @ design.g_test[e][np.ix_(idx, idx)] @ x)
                   / max(design.n_test[e], 1) for e in range(3)])
    live = design.n_test > 0
    per_eq = np.sqrt(np.maximum(ms, 0.0))
    score = float(np.sqrt(np.mean(ms[live]))) if live.any() else math.inf
    return Fitted((), tuple(int(j) for j in idx), x, cost, score, per_eq)


def fit_model(design: Design, items: Sequence[str], tol: float) -> Fitted:
    """Fit a model (module doc): shaped effects take their best grid column by training cost and its better
    neighbour (:func:`_shape_columns`)."""
    base = [j for c in (*CONSTANTS, *NUISANCES) for j in design.index(c)]
    named = {i for i in items if i in CONSTANTS}
    chosen: list[int] = list(base)
    for item in items:
        if item in CONSTANTS:
            continue
        js = design.index(item)
        shapes = sorted({design.columns[j].shape for j in js if not math.isnan(design.columns[j].shape)})
        if design.columns[js[0]].item == "cogging" or not shapes:
            chosen += js
            continue
        chosen += _shape_columns(design, chosen, js, named, tol, mix=item not in SATURATING)
    f = _filtered(design, solve(design, chosen, named, tol), chosen, named, tol)
    return Fitted(tuple(items), f.cols, f.x, f.train_cost, f.score, f.per_eq)


def _filtered(design: Design, f: Fitted, chosen: list[int], named: set[str], tol: float) -> Fitted:
    """``f`` refitted with ``L``'s box widened above by the current filter it fits: a current lag of ``l`` samples
    (``current_lag``, eq. dc_mechanical) raises the apparent inductance in eq. dc_electrical by ``l dt R / L``
    (:attr:`.regression.Design.lag_inductance`), the logger's. One refit where L's box binds suffices."""
    js, lag_j = design.index("L"), design.index("current_lag")
    if design.lag_inductance <= 0 or "L" in named or not js or not lag_j or "L" in design.unresolved:
        return f
    lag, x = f.coefficient(lag_j[0]), f.coefficient(js[0])
    top = tol + design.slack.get("L", 0.0) + design.above.get("L", 0.0)
    if lag <= 0 or x < top - 1e-9:
        return f
    return solve(design, chosen, named, tol, {**design.above, "L": design.above.get("L", 0.0)
                                              + lag * design.lag_inductance})


def _shape_columns(design: Design, chosen: list[int], js: list[int], named: set[str], tol: float,
                   mix: bool = True) -> list[int]:
    """A shaped effect's columns: the best grid column ``js`` (ordered by shape) by training cost, with
    (``mix``) the better of its grid neighbours (both coefficients sign-bounded): the true shape lies between grid
    points, and the residual of one grid column mis-shaped by half a grid step (e.g. a wake lag 30 % off) would be
    explained by a wrong constant instead. (A saturating effect's amplitude is bounded by its width instead.)"""
    costs = [solve(design, [*chosen, j], named, tol).train_cost for j in js]
    k = int(np.argmin(costs))
    pairs = [[js[k], js[m]] for m in (k - 1, k + 1) if mix and 0 <= m < len(js)]
    fits = [(solve(design, [*chosen, *pr], named, tol).train_cost, pr) for pr in pairs]
    return min(fits, key=lambda e: e[0])[1] if fits else [js[k]]


@dataclass(frozen=True)
class Step:
    """One forward-selection round: the model before, every challenger's fit, and the adopted one (or None)."""

    before: Fitted
    tried: list[tuple[str, Fitted]]
    adopted: str | None


@dataclass(frozen=True)
class Selection:
    final: Fitted
    steps: list[Step]
    ambiguous: list[dict[str, object]]
    #: items adopted in a forward step that no longer win beside the other adopted items (not named)
    dropped: list[str] = field(default_factory=list)


def select(design: Design, pool: Sequence[str], tol: float, min_improvement: float, noise_floor: float,
           max_items: int, margin: float, progress: Callable[[float], None] | None = None,
           physical: Callable[[Fitted], bool] = lambda f: True) -> Selection:
    """Forward selection over ``pool`` (effects and constants), then the ambiguity challenge (module doc).
    Constants the log cannot resolve (:attr:`.regression.Design.unresolved`) are calibrated, never named;
    ``min_improvement`` applies to effects (a constant's materiality is ``tol``). A model that ``physical``
    refuses (an effect fitted outside its catalogue range, e.g. a Stribeck level of 1.8e4 N m) is never adopted."""
    pool = [c for c in pool if c not in design.unresolved and design.index(c)]  # (no columns: not testable here)
    items: list[str] = []
    current = fit_model(design, items, tol)
    steps: list[Step] = []
    while len(items) < max_items:
        tried = [(c, fit_model(design, [*items, c], tol)) for c in pool if c not in items]
        tried.sort(key=lambda e: e[1].score)
        tried = _prefer_effects(design, tried, margin)
        if progress is not None:
            progress((len(items) + 1) / (max_items + 1))
        # the best-scoring item whose win passes its test (they differ: materiality, one equation's scatter)
        win = next((k for k, (c, f) in enumerate(tried) if _wins(design, current, c, f, min_improvement)
                    and physical(f) and _room(design, current, (c,), noise_floor)), None) \
            if _worst(design, current) > noise_floor else None
        if win is not None:
            tried = [tried[win], *tried[:win], *tried[win + 1:]]
        ok = win is not None
        pair = None if ok or len(items) + 2 > max_items else \
            _pair(design, items, tried, current, tol, min_improvement, noise_floor, physical)
        if pair is not None:  # two items that clear the test only together
            steps += pair
            items += [st.adopted for st in pair if st.adopted is not None]
            current = pair[-1].tried[0][1]
            continue
        steps.append(Step(current, tried, tried[0][0] if ok else None))
        if not ok:
            break
        items.append(tried[0][0])
        current = tried[0][1]
    dropped = []
    # backward: each constant, then each effect but the last adopted one, tested again beside all the others
    for c in [i for i in items if i in CONSTANTS] + [i for i in items if i not in CONSTANTS][:-1]:
        rest = fit_model(design, [i for i in items if i != c], tol)
        if not _wins(design, rest, c, current, min_improvement):
            items.remove(c)
            dropped.append(c)
            current = rest
    return Selection(current, steps, _challenge(design, items, pool, current, tol, margin), dropped)


def _pair(design: Design, items: list[str], tried: list[tuple[str, Fitted]], current: Fitted, tol: float,
          min_improvement: float, noise_floor: float, physical: Callable[[Fitted], bool]) -> list[Step] | None:
    """Two of the :data:`PAIR_TOP` best challengers adopted together, where none clears the test alone: two effects
    whose residuals overlap (an angle ripple beside Coulomb friction: each alone leaves the other's residual,
    fitted into the wrong columns). The pair must clear the test against ``current`` (the score falling by
    ``min_improvement`` and beyond sampling noise) and against either item alone (each is needed beside the
    other). Returns the two forward steps (the better single first), or None."""
    if len(tried) < 2 or _worst(design, current) <= noise_floor:
        return None
    single = dict(tried[:PAIR_TOP])
    fits = [(a, b, fit_model(design, [*items, a, b], tol)) for a, b in itertools.combinations(single, 2)]
    a, b, f = min(fits, key=lambda e: e[2].score)
    if not physical(f) or not _room(design, current, (a, b), noise_floor):
        return None
    for before in (current, single[a], single[b]):
        if not _material(design, before, f, (a, b), min_improvement) or not _beyond_scatter(design, before, f):
            return None
    return [Step(current, [(a, single[a]), *[e for e in tried if e[0] != a]], a), Step(single[a], [(b, f)], b)]


def _acts(design: Design, items: Sequence[str]) -> np.ndarray:
    """(3,) the equations some column of ``items`` enters."""
    js = [j for item in items for j in design.index(item)]
    return np.any(design.g_train[:, js, js] > 0, axis=1)


def _room(design: Design, current: Fitted, items: Sequence[str], noise_floor: float) -> bool:
    """Whether some equation ``items`` enter is above ``noise_floor`` in ``current`` (held-out RMS, noise units):
    an equation already at its noise has nothing left for them to explain, whatever another equation holds."""
    live = (design.n_test > 0) & _acts(design, items)
    return bool(np.any(current.per_eq[live] > noise_floor))


def _wins(design: Design, current: Fitted, item: str, f: Fitted, min_improvement: float) -> bool:
    """Whether adding ``item`` (fitted ``f``) to ``current`` wins on held-out data: beyond sampling noise
    (:func:`_beyond_scatter`), and for an effect by ``min_improvement`` too (a constant's materiality is the
    tolerance, module doc)."""
    material = item in CONSTANTS or _material(design, current, f, (item,), min_improvement)
    if not material:
        return False
    return _beyond_scatter(design, current, f) or (item in CONSTANTS and (_blocks_agree(design, current, item, f)
                                                                         or _ratio_agrees(design, current, item, f))) \
        or (item == "cogging" and _ripple_beyond(design, current, f))


def _ripple_beyond(design: Design, before: Fitted, after: Fitted) -> bool:
    """Whether an angle ripple's fall of the torque equation's held-out RMS is beyond two standard errors over
    the rows independent for the ripple (``design.angle["independence"]``, :func:`.angle.ripple_independence`):
    a fast ripple decorrelates from a slow residual within a period, not within the rotor time constant."""
    frac = float(design.angle.get("independence", 0.0))  # type: ignore[arg-type]
    n = max(float(design.n_test[0]) * frac, 1.0)
    return before.per_eq[0] > 0 and 1.0 - after.per_eq[0] / before.per_eq[0] >= math.sqrt(2.0 / n)


def _material(design: Design, before: Fitted, after: Fitted, items: Sequence[str], min_improvement: float) -> bool:
    """Whether ``after`` (``before`` plus the effects ``items``) cuts the held-out score by ``min_improvement``
    (an effect's materiality), the score taken with every equation that no column of ``items`` enters counted at
    most at its noise level (:func:`_capped_score`): an error there (a command timing the alignment left in the
    armature equation, say) is one these effects can neither explain nor be blamed for, and averaged into the
    score it would dilute the fall they bring where they act (a torque ripple halving the torque equation's
    error beside an armature equation at 18 noise units moved the pooled score by 0.5 %)."""
    acts = _acts(design, items)
    return _capped_score(design, after, acts) <= (1.0 - min_improvement) * _capped_score(design, before, acts)


def _capped_score(design: Design, f: Fitted, acts: np.ndarray) -> float:
    """The held-out score of ``f`` (as :attr:`Fitted.score`) with the equations outside ``acts`` (3,) counted at
    most at the noise level (1 in noise units)."""
    live = design.n_test > 0
    if not live.any():
        return math.inf
    per_eq = np.where(acts, f.per_eq, np.minimum(f.per_eq, 1.0))
    return float(np.sqrt(np.mean(per_eq[live] ** 2)))


def _blocks_agree(design: Design, current: Fitted, item: str, f: Fitted) -> bool:
    """Whether a constant freed beyond the tolerance (``f``) fits the held-out data better than ``current`` in a
    PAIRED comparison over the held-out blocks (:func:`block_t`): some equation's squared error falls, block by
    block, beyond the one-sided :data:`BLOCK_ALPHA` quantile of Student's t (the blocks' own scatter; nested models
    compared on the same rows need far less than the unpaired :func:`_beyond_scatter`, which holds each RMS to its
    own sampling noise). Only a plausible error (within :data:`IMPLAUSIBLE_FACTOR` of nominal) is named so."""
    if _factor(design, f, item) is not None:
        return False
    t, nb = block_t(design, current, f)
    if nb < BLOCK_MIN:
        return False
    material = (design.n_test > 0) & (f.per_eq <= (1.0 - BLOCK_FALL) * current.per_eq)
    return bool(np.any(material & (t >= stats.t.ppf(1.0 - BLOCK_ALPHA, nb - 1))))


def _ratio_agrees(design: Design, current: Fitted, item: str, f: Fitted) -> bool:
    """Whether a constant freed beyond the tolerance (``f``, nested over ``current``: one box opened) wins a
    held-out likelihood-ratio test (:func:`ratio_z`) in the TORQUE equation, if its column enters it: the held-out
    squared error falls beyond the one-sided :data:`BLOCK_ALPHA` normal quantile, by :data:`BLOCK_FALL` of its RMS
    at least, the blocks agreeing in sign (:func:`block_t`). The speed view's rows are few and correlated: with four
    to six blocks the block test's Student quantile (3.4-4.5) left a change of a third of the torque error unnamed,
    while the fall's scatter is known from the residual. (Not the armature equation: a current filter the torque
    rows do not show adds ``R t_f i'`` there, L's own column, so its residual is not noise alone.) Only a plausible
    error (within :data:`IMPLAUSIBLE_FACTOR`) is named so."""
    if _factor(design, f, item) is not None:
        return False
    (t, nb), js = block_t(design, current, f), design.index(item)
    enters = bool(np.any(design.g_train[0, js, js] > 0)) and design.n_test[0] > 0  # eq. dc_mechanical only
    return enters and bool(nb < 2 or t[0] > 0) and f.per_eq[0] <= (1.0 - BLOCK_FALL) * current.per_eq[0] \
        and ratio_z(design, current, f)[0] >= stats.norm.ppf(1.0 - BLOCK_ALPHA)


def ratio_z(design: Design, before: Fitted, after: Fitted) -> np.ndarray:
    """Per equation (3,): the held-out squared error's fall from ``before`` to ``after`` (nested) in standard
    errors: with ``d`` the fitted prediction's change on the held-out rows and ``r`` ``after``'s residual there, the
    fall is ``2 r'd + d'd``, and ``r'd`` scatters by ``s sqrt(d'd / q)`` over rows of noise ``s`` independent in a
    fraction ``q`` (:attr:`.regression.Design.independence`); conservative under ``before`` (``2 r'd - d'd``)."""
    cols = sorted(set(before.cols) | set(after.cols))

    def full(f: Fitted) -> np.ndarray:
        v = np.zeros(len(cols))
        v[[cols.index(j) for j in f.cols]] = f.x
        return v

    d = full(after) - full(before)
    idx = np.array(cols, dtype=int)
    dd = np.array([float(d @ design.g_test[e][np.ix_(idx, idx)] @ d) for e in range(3)])
    fall = (before.per_eq ** 2 - after.per_eq ** 2) * design.n_test
    sd = 2.0 * after.per_eq * np.sqrt(np.maximum(dd, 0.0) / np.maximum(design.independence, 1e-12))
    return np.where(sd > 0, fall / np.maximum(sd, 1e-300), 0.0)


def _prefer_effects(design: Design, tried: list[tuple[str, Fitted]], margin: float) -> list[tuple[str, Fitted]]:
    """``tried`` (best first) with an effect moved first where the best item is a constant corrected beyond
    :data:`IMPLAUSIBLE_FACTOR` of its nominal (x > 100 % or x < -50 %) and the effect's held-out score is as
    good (within ``margin`` or :func:`_scatter`, as in the ambiguity challenge, which then reports the two):
    a datasheet constant twice or half its value is a less likely error than a missing effect."""
    if not tried or _factor(design, tried[0][1], tried[0][0]) is None:
        return tried
    best = tried[0][1]
    tie = max(margin, _scatter(design))
    for k, (other, f) in enumerate(tried[1:], 1):
        if other not in CONSTANTS and f.score <= best.score * (1.0 + tie):
            return [tried[k], *tried[:k], *tried[k + 1:]]
    return tried


def _scatter(design: Design) -> float:
    """Two standard errors of a held-out RMS over its independent rows, ``2 / sqrt(2 n)`` (relative), the rows of
    all equations pooled at the torque rows' independence (the fewest): a smaller fall of the score is
    sampling noise (low-passed rows are correlated, :attr:`Design.independence`)."""
    live = design.n_test > 0
    return 2.0 / math.sqrt(2.0 * max(float(design.n_test[live].sum() * design.independence.min()), 1.0))


def _beyond_scatter(design: Design, before: Fitted, after: Fitted) -> bool:
    """Whether ``after``'s held-out fit is better than ``before``'s beyond sampling noise: the score falls by more
    than :func:`_scatter`, or one equation's held-out RMS falls by more than two standard errors over ITS
    independent rows (``sqrt(2 / n_e)``): an electrical item need not clear the torque rows' scatter."""
    if after.score <= (1.0 - _scatter(design)) * before.score:
        return True
    live = (design.n_test > 0) & (before.per_eq > 0)
    n = np.maximum(design.n_test * design.independence, 1.0)
    fall = 1.0 - after.per_eq[live] / before.per_eq[live]
    return bool(np.any(fall >= np.sqrt(2.0 / n[live])))


def block_t(design: Design, before: Fitted, after: Fitted) -> tuple[np.ndarray, int]:
    """Paired comparison over the held-out blocks (:attr:`.regression.Design.g_blocks`): per equation (3,), the
    mean fall of the squared error from ``before`` to ``after`` over the blocks, in standard errors of that mean
    (the blocks' own scatter: whatever the rows' correlation and whatever the residual holds); and the number
    of blocks. Gram-matrix algebra only."""
    nb = design.c_blocks.shape[0]
    if nb < 2:
        return np.zeros(3), nb

    def sse(f: Fitted) -> np.ndarray:  # (nb, 3)
        idx = np.array(f.cols, dtype=int)
        g = design.g_blocks[:, :, idx][:, :, :, idx]
        return design.c_blocks - 2 * design.h_blocks[:, :, idx] @ f.x + np.einsum("q,beqr,r->be", f.x, g, f.x)

    d = sse(before) - sse(after)
    sd = d.std(axis=0, ddof=1)
    t = np.where(sd > 0, d.mean(axis=0) / np.maximum(sd, 1e-300) * math.sqrt(nb), 0.0)
    return t, nb


def _worst(design: Design, f: Fitted) -> float:
    """The worst-fitting equation's held-out RMS [noise units]: one equation above the noise is enough to go
    on (the combined score averages it with the equations that already fit)."""
    live = design.n_test > 0
    return float(np.max(f.per_eq[live])) if live.any() else math.inf


def _challenge(design: Design, items: list[str], pool: Sequence[str], best: Fitted, tol: float,
               margin: float) -> list[dict[str, object]]:
    """Adopted items that another item explains as well on held-out data: within ``margin``, or within the
    held-out score's own sampling scatter (:func:`_scatter`), whichever is wider. Where the alternative is a
    constant off by more than :data:`IMPLAUSIBLE_FACTOR`, the reason says why the effect was preferred."""
    margin = max(margin, _scatter(design))
    out = []
    for a, b in itertools.product(items, pool):
        if b in items:
            continue
        alt = fit_model(design, [b if i == a else i for i in items], tol)
        na, nb = (f"param:{x}" if x in CONSTANTS else x for x in (a, b))
        if alt.score <= best.score * (1.0 + margin):
            out.append({"adopted": a, "alternative": b, "score": best.score, "alternative_score": alt.score,
                        "reason": f"replacing {na} by {nb} fits the held-out data as well "
                                  f"({alt.score:.3g} vs {best.score:.3g} noise units, within {100 * margin:.1f} %): "
                                  f"this log cannot tell them apart{_prior_note(design, alt, a, b)}"})
    return out


def _factor(design: Design, f: Fitted, item: str) -> float | None:
    """True / nominal of constant ``item`` in ``f`` where beyond :data:`IMPLAUSIBLE_FACTOR` either way, else None."""
    if item not in CONSTANTS:
        return None
    factor = 1.0 + f.coefficient(design.index(item)[0])
    return factor if max(factor, 1.0 / max(factor, 1e-9)) > IMPLAUSIBLE_FACTOR else None


def _prior_note(design: Design, alt: Fitted, adopted: str, const: str) -> str:
    """Why the adopted effect beat the alternative constant ``const`` fitted in ``alt`` (:func:`_prefer_effects`)."""
    factor = _factor(design, alt, const)
    if factor is None or adopted in CONSTANTS:
        return ""
    return (f"; {adopted} is preferred: param:{const} would have to be {factor:.2g} x its nominal, a less likely "
            f"error than a missing effect (beyond a factor {IMPLAUSIBLE_FACTOR:g})")
