"""Held-out evidence that one fitted model beats another, over the Gram matrices of :mod:`.regression`: the
fit record (:class:`Fitted`) and the tests :mod:`.select` combines. A fall of the held-out error counts when it is
beyond sampling noise (:func:`beyond_scatter`, :func:`ripple_beyond`), material (:func:`is_material`), or, for nested
models scored on the same rows, beyond a paired comparison over held-out blocks (:func:`blocks_agree`) or a
likelihood ratio (:func:`ratio_agrees`); a constant also on its estimate, the held-out blocks agreeing
(:func:`estimate_agrees`). Scores are in noise units (about 1 for a model at the noise)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtri, stdtrit

from ocp.identify.regression import CONSTANTS, Design

#: a constant off by more than this factor (either way) is a less likely error than a missing effect that fits
#: the held-out data as well: the prior on constant errors behind :func:`.select._prefer_effects`
IMPLAUSIBLE_FACTOR = 2.0
#: ... judged on the fitted factor's bound nearest nominal, this many standard errors in
PRIOR_SE = 2.0
#: the paired block test of a constant (:func:`blocks_agree`): one-sided level, and the fewest held-out blocks
BLOCK_ALPHA = 0.01
#: ... the level an EFFECT's likelihood ratio is held to (:func:`ratio_agrees`): a round tries about ten effects
#: (and shapes of each) against one constant's freed box, so each at a tenth of a constant's level keeps a round's
#: chance of a false adoption near :data:`BLOCK_ALPHA` (at 1 % a drag asymmetry was named for the 1.8-noise-unit
#: residual a Coulomb column leaves on the project's own rig log, z = 2.39)
EFFECT_ALPHA = 0.001
BLOCK_MIN = 4
#: ... and the fall of that equation's held-out RMS it needs (the tolerance's own 10 %: a constant's materiality)
BLOCK_FALL = 0.10
#: the estimate test of a constant (:func:`estimate_agrees`): its freed estimate this many standard errors beyond the
#: value its calibration box holds it at ...
ESTIMATE_SE = 3.0
#: ... and beyond it by this fraction of that value too (half the tolerance beyond it: a bias its standard error
#: does not hold, set after the blind rig's 403 in :func:`estimate_agrees`'s doc) ...
ESTIMATE_MARGIN = 0.5
#: ... and the held-out blocks agreeing at this one-sided level (a standard 2.5 %, chosen after looking at 6019 in
#: :func:`estimate_agrees`'s doc, where 5 % named a clean log's bias)
ESTIMATE_ALPHA = 0.025
#: an equation's held-out error under this many noise units is counted at it where an effect's fall is judged
#: (:func:`resolved`): below it the residual is the method's own (filters, integrator), not a missing effect
RESOLVED = 0.2


@dataclass(frozen=True)
class Fitted:
    """A model fitted on training rows: its items, chosen columns, coefficients, training cost, held-out score."""

    items: tuple[str, ...]
    cols: tuple[int, ...]
    x: np.ndarray
    train_cost: float
    score: float
    per_eq: np.ndarray  # held-out RMS per equation [sigma units], (3,)
    #: under cross-validation (:attr:`.regression.Design.g_fold`), the model fitted for each fold (whose held-out
    #: errors make ``per_eq``); ``cols``/``x`` are then fitted on all rows
    folds: tuple[Fitted, ...] = ()
    #: the nominal model as given, nothing fitted (:func:`.lsq.as_given`): it predicts the held-out rows better than
    #: the calibrated fit
    as_given: bool = False

    def coefficient(self, j: int) -> float:
        return float(self.x[self.cols.index(j)]) if j in self.cols else 0.0


def equations_of(design: Design, items: Sequence[str]) -> np.ndarray:
    """(3,) the equations some column of ``items`` enters."""
    js = [j for item in items for j in design.index(item)]
    return np.any(design.g_train[:, js, js] > 0, axis=1)


def own_scatter(design: Design) -> np.ndarray:
    """(3,) two standard errors of each equation's held-out RMS over ITS independent rows, ``sqrt(2 / n_e)``
    (relative; :attr:`.regression.Design.independence`)."""
    return np.sqrt(2.0 / np.maximum(design.n_held * design.independence, 1.0))


def at_noise(design: Design, f: Fitted) -> np.ndarray:
    """(3,) whether ``f`` leaves each equation at its noise: within :func:`own_scatter` of one noise unit."""
    return f.per_eq <= 1.0 + own_scatter(design)


def ripple_rows(design: Design) -> float:
    """The held-out torque rows independent for the ripple (``design.angle["independence"]``,
    :func:`.angle.ripple_independence`; at least one): a fast ripple decorrelates from a slow residual within a
    period, not within the rotor time constant."""
    frac = float(design.angle.get("independence", 0.0))  # type: ignore[arg-type]
    return max(float(design.n_held[0]) * frac, 1.0)


def ripple_beyond(design: Design, before: Fitted, after: Fitted) -> bool:
    """Whether an angle ripple's fall of the torque equation's held-out RMS is beyond two standard errors over
    the rows independent for it (:func:`ripple_rows`)."""
    return before.per_eq[0] > 0 and 1.0 - after.per_eq[0] / before.per_eq[0] >= math.sqrt(2.0 / ripple_rows(design))


def win_test(design: Design, current: Fitted, item: str, f: Fitted, min_improvement: float) -> str | None:
    """The first test by which adding ``item`` (fitted ``f``) to ``current`` wins on held-out data, or None: the
    likelihood ratio (``likelihood_ratio``, :func:`ratio_agrees`) or a fall beyond sampling noise
    (``beyond_sampling``, :func:`beyond_scatter`); for a constant also the paired held-out blocks
    (``held_out_blocks``, :func:`blocks_agree`) or its estimate (``estimate``, :func:`estimate_agrees`), for an angle
    ripple its own independent rows (``ripple_rows``, :func:`ripple_beyond`). An effect must be material as well
    (:func:`is_material`; an angle ripple on the torque equation alone where it wins, :func:`own_material`, and
    beside a Stribeck band off the band too, :func:`ripple_off_band`); a constant's materiality is the tolerance (the
    selection's module doc). The selection adopts by it (:func:`.select.select`), and the answer names the test each
    name won by (:mod:`.strength`): one function, so the name and the reason given cannot part."""
    material = item in CONSTANTS or is_material(design, current, f, (item,), min_improvement)
    if not (material or (item == "cogging" and own_material(design, current, f, (item,), min_improvement))):
        return None
    if item == "cogging" and not ripple_off_band(design, current, f, min_improvement):
        return None
    if ratio_agrees(design, current, item, f):
        return "likelihood_ratio"
    if beyond_scatter(design, current, f, (item,)):
        return "beyond_sampling"
    if not material:
        return None
    if item in CONSTANTS and blocks_agree(design, current, item, f):
        return "held_out_blocks"
    if item in CONSTANTS and estimate_agrees(design, current, item, f):
        return "estimate"
    return "ripple_rows" if item == "cogging" and ripple_beyond(design, current, f) else None


def is_material(design: Design, before: Fitted, after: Fitted, items: Sequence[str], min_improvement: float) -> bool:
    """Whether ``after`` (``before`` plus the effects ``items``) cuts the held-out score by ``min_improvement`` (an
    effect's materiality), the score taken with every equation that no column of ``items`` enters counted at most at
    its noise level and those they enter at least at :data:`RESOLVED` (:func:`capped_score`): an error there (a
    command timing the alignment left in the armature equation, say) is one these effects can neither explain nor be
    blamed for, and averaged into the score it would dilute the fall they bring where they act (a torque ripple
    halving the torque equation's error beside an armature equation at 18 noise units moved the pooled score by
    0.5 %). A banded effect (a Stribeck band, :data:`.footprint.BANDED`) acts on a few rows of those equations too:
    its fall counts as well on the held-out rows where its column acts (:func:`band_score`; proving-ground seed
    6003, 2 kHz: 21 mN m of Stribeck friction acting on 5 % of the held-out rows cut the torque equation's error
    there by 24 %, the score by 11 %)."""
    acts = equations_of(design, items)
    if capped_score(design, after, acts) <= (1.0 - min_improvement) * capped_score(design, before, acts):
        return True
    j = band_of(design, after, items)
    return j is not None and \
        band_score(design, after, j, acts) <= (1.0 - min_improvement) * band_score(design, before, j, acts)


def own_material(design: Design, before: Fitted, after: Fitted, items: Sequence[str], min_improvement: float) -> bool:
    """Whether ``after`` (``before`` plus the effects ``items``) cuts the held-out RMS pooled over the equations
    ``items`` enter, alone, by ``min_improvement``: an angle ripple's materiality where it also wins beyond
    sampling noise or by the likelihood ratio (:func:`win_test`). Counted at the noise level, the equations it
    cannot enter dilute its fall wherever its own equation reads near or under one noise unit, which is an estimate:
    the blind rig's seed 368 (5 kHz), an 18-period ripple took the torque equation from 0.68 to 0.18 noise units, a
    capped score's fall of 8 %. Each equation is counted at least at :data:`RESOLVED`."""
    live = equations_of(design, items) & (design.n_test > 0)
    if not live.any():
        return False
    was, now = (float(np.sqrt(np.mean(resolved(f.per_eq[live]) ** 2))) for f in (before, after))
    return now <= (1.0 - min_improvement) * was


def band_of(design: Design, f: Fitted, items: Sequence[str]) -> int | None:
    """The first column of ``f`` that is a band of one of ``items`` (:class:`.footprint.Footprints`), or None."""
    prints = design.footprint
    if prints is None:
        return None
    return next((j for j in f.cols if j in prints and design.columns[j].item in items), None)


def band_fall(design: Design, before: Fitted, after: Fitted, item: str) -> tuple[float, float] | None:
    """For a banded ``item`` fitted in ``after``: the fall of the held-out error from ``before`` on the rows its band
    acts on (a fraction, :func:`band_score`), and those rows' share of the held-out rows; None for another item."""
    j = band_of(design, after, (item,))
    if j is None or design.footprint is None:
        return None
    acts = equations_of(design, (item,))
    was, now = band_score(design, before, j, acts), band_score(design, after, j, acts)
    rows = design.footprint.grams(j)[3].sum(axis=0)
    share = float(np.max(rows[acts]) / max(float(np.max(design.n_test[acts])), 1.0)) if acts.any() else 0.0
    return (1.0 - now / was if 0.0 < was < math.inf else 0.0), share


def band_score(design: Design, f: Fitted, j: int, acts: np.ndarray) -> float:
    """The held-out score of ``f`` on the rows where banded column ``j`` acts (:attr:`.regression.Design.footprint`)
    in the equations ``acts`` (3,): each fold's rows scored by the model fitted without them, each equation counted
    at least at :data:`RESOLVED`."""
    assert design.footprint is not None  # (a fold's design has none: scored at the top level only)
    g, h, c, n = design.footprint.grams(j)
    total = held_sse(f, g, h, c)
    rows = n.sum(axis=0)
    live = acts & (rows > 0)
    return float(np.sqrt(np.mean(np.maximum(total[live] / rows[live], RESOLVED**2)))) if live.any() else math.inf


def off_band_fall(design: Design, before: Fitted, after: Fitted) -> float:
    """The fall (a fraction) of the torque equation's held-out error from ``before`` to ``after`` on the held-out
    rows where ``after``'s Stribeck band (:data:`.footprint.BANDED`) does NOT act (each fold's rows scored by the model
    fitted without them, as :func:`band_score`); ``inf`` without a band or without a held-out row (or error) off it:
    nothing there to judge a ripple on (a run dwelling at low speed, where the band covers every row), and the other
    tests decide alone."""
    j = band_of(design, after, ("stribeck",))
    if j is None or design.footprint is None:
        return math.inf
    band = design.footprint.grams(j)[:3]
    held = (design.g_fold, design.h_fold, design.c_fold) if design.folds else \
        (design.g_test[None], design.h_test[None], design.c_test[None])
    sse = [max(float(held_sse(f, *held)[0] - held_sse(f, *band)[0]), 0.0) for f in (before, after)]
    return 1.0 - math.sqrt(sse[1] / sse[0]) if sse[0] > 0 else math.inf


def held_sse(f: Fitted, g: np.ndarray, h: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(3,) ``f``'s held-out squared error per equation over the rows whose Gram matrices per fold are ``g``
    (K, 3, Q, Q), ``h`` (K, 3, Q), ``c`` (K, 3): each fold's rows scored by the model fitted without them
    (:attr:`Fitted.folds`; one split, K = 1: ``f`` itself)."""
    total = np.zeros(3)
    for k, fk in enumerate(f.folds or (f,)):
        idx = np.array(fk.cols, dtype=int)
        total += c[k] - 2.0 * h[k][:, idx] @ fk.x + np.einsum("q,eqr,r->e", fk.x, g[k][:, idx][:, :, idx], fk.x)
    return total


def ripple_off_band(design: Design, before: Fitted, after: Fitted, min_improvement: float) -> bool:
    """Whether an angle ripple (``after``: ``before`` plus ``cogging``) beside a Stribeck band is material
    (``min_improvement``) on the torque equation's held-out rows where the band does not act (:func:`off_band_fall`);
    True without a band or a row off it. A ripple is periodic in the angle and shows wherever the log resolves it; one
    that helps only where the band acts takes up the band's misfit (on 6 proving-ground logs with Stribeck friction and
    a ripple named falsely beside it the fall off the band was -0.01 to 0.28; on 17 with both drawn and named, 0.30 to
    0.97: bench/modelcheck.py --kind two, seeds 50015..52555 with both drawn)."""
    return off_band_fall(design, before, after) >= min_improvement


def band_alike(design: Design, item: str, best: Fitted, alt: Fitted, margin: float) -> bool:
    """Whether ``alt`` fits the rows where ``item``'s band acts within ``margin`` of ``best``, for a banded ``item``
    (a Stribeck band: its materiality is judged on those rows too, :func:`is_material`); True for any other item.
    Else the pooled score, which those rows barely move, would call a thrust-equation item its equal."""
    j = band_of(design, best, (item,))
    if j is None:
        return True
    acts = equations_of(design, (item,))
    return band_score(design, alt, j, acts) <= band_score(design, best, j, acts) * (1.0 + margin)


def acts_alike(design: Design, item: str, best: Fitted, alt: Fitted, margin: float) -> bool:
    """Whether ``alt`` fits every equation ``item`` enters within that equation's own sampling scatter (two standard
    errors over its independent rows, ``sqrt(2 / n_e)``, or ``margin``, the wider) of ``best``. An item adopted on
    one equation's fall (:func:`beyond_scatter`) is not matched by an alternative that leaves that equation as it
    was, however wide the pooled score's scatter (the torque rows' independence, :func:`scatter`): without this,
    every item of the pool was listed as its equal (the blind rig, ``bench/blind_check.py``: 10 of 200 logs listed
    12-15 alternatives, e.g. a thrust lag for a motor constant)."""
    acts = equations_of(design, (item,)) & (design.n_test > 0) & (best.per_eq > 0)
    wide = np.maximum(margin, own_scatter(design))
    return bool(np.all(alt.per_eq[acts] <= best.per_eq[acts] * (1.0 + wide[acts])))


def capped_score(design: Design, f: Fitted, acts: np.ndarray) -> float:
    """The held-out score of ``f`` (as :attr:`Fitted.score`) with the equations outside ``acts`` (3,) counted at
    most at the noise level (1 in noise units)."""
    live = design.n_test > 0
    if not live.any():
        return math.inf
    per_eq = np.where(acts, resolved(f.per_eq), np.minimum(f.per_eq, 1.0))
    return float(np.sqrt(np.mean(per_eq[live] ** 2)))


def resolved(per_eq: np.ndarray) -> np.ndarray:
    """Held-out errors ``per_eq`` (noise units) counted at least at :data:`RESOLVED`."""
    return np.maximum(per_eq, RESOLVED)


def blocks_agree(design: Design, current: Fitted, item: str, f: Fitted) -> bool:
    """Whether a constant freed beyond the tolerance (``f``) fits the held-out data better than ``current`` in a
    PAIRED comparison over the held-out blocks (:func:`block_t`): some equation's squared error falls, block by
    block, beyond the one-sided :data:`BLOCK_ALPHA` quantile of Student's t (the blocks' own scatter; nested models
    compared on the same rows need far less than the unpaired :func:`beyond_scatter`, which holds each RMS to its
    own sampling noise). Only a plausible error (within :data:`IMPLAUSIBLE_FACTOR` of nominal) is named so."""
    if implausible_factor(design, f, item) is not None:
        return False
    t, nb = block_t(design, current, f)
    if nb < BLOCK_MIN:
        return False
    material = (design.n_test > 0) & (f.per_eq <= (1.0 - BLOCK_FALL) * current.per_eq)
    return bool(np.any(material & (t >= stdtrit(nb - 1, 1.0 - BLOCK_ALPHA))))


def estimate_agrees(design: Design, current: Fitted, item: str, f: Fitted) -> bool:
    """Whether a constant freed beyond the tolerance (``f``) is named on its ESTIMATE, where its equation is too noisy
    for :func:`blocks_agree`'s fall of :data:`BLOCK_FALL`: the freed estimate lies :data:`ESTIMATE_SE` standard
    errors (:func:`standard_error`) beyond the value ``current`` boxes it at, and by :data:`ESTIMATE_MARGIN` of that
    value (half the tolerance beyond it: the blind rig's 403, every constant right, named ``R`` +11.9 % at 5.8
    standard errors, a bias of the model's misfit its standard error does not hold), and in an equation it enters the
    held-out data agree -- the paired blocks' t (:func:`block_t`) or the likelihood ratio's z (:func:`ratio_z`) beyond
    the one-sided :data:`ESTIMATE_ALPHA` quantile -- and ``f`` leaves that equation at its noise (:func:`at_noise`).
    The materiality of a constant is its tolerance (module doc of :mod:`.select`), read here on the estimate instead
    of on the held-out RMS: a ``B`` 48 % off beside a drag asymmetry took the torque equation from 1.145 to 1.076
    noise units, a fall of 6 % (proving ground 14142: t 3.41 over 126 blocks; its estimate 7 standard errors beyond
    its box). The standard error holds only where what is left is noise: in an equation still above it, a misfit the
    model lacks biases the estimate (the blind rig, at a one-sided 2.5 % without that condition: 17, 28 and 51 named
    a true ``B`` 39-121 % off, 3.6-6.6 standard errors beyond its box, t 2.7-8.2 over 72-466 blocks, for falls of
    2-6 % that left the torque equation at 1.38-1.59 noise units). Not ``L``: the command timing and the current
    filter bias its estimate beyond its standard error (45, 23170, 6194: ``L`` freed 4-9 standard errors beyond its
    box, t 3.3-10.9 for a fall of 1-3 %); :mod:`.inductance` judges it. At a one-sided 5 % a clean 50 Hz log named
    ``B`` 19 % low (6019: 3.6 standard errors, t 1.79 over 27 blocks, z 0.93, the torque equation at 1.04): a bias of
    the coarse sampling. Only a plausible error (within :data:`IMPLAUSIBLE_FACTOR`) is named so."""
    if item == "L" or implausible_factor(design, f, item) is not None:
        return False
    j = design.index(item)[0]
    se = standard_error(design, f, j)
    boxed = current.coefficient(j)
    if not se > 0 or abs(f.coefficient(j) - boxed) < max(ESTIMATE_SE * se, ESTIMATE_MARGIN * abs(boxed)):
        return False
    t, nb = block_t(design, current, f)
    if nb < BLOCK_MIN:
        return False
    agree = (t >= stdtrit(nb - 1, 1.0 - ESTIMATE_ALPHA)) | (ratio_z(design, current, f) >= ndtri(1.0 - ESTIMATE_ALPHA))
    return bool(np.any(agree & at_noise(design, f) & (design.n_test > 0) & equations_of(design, (item,))))


def ratio_agrees(design: Design, current: Fitted, item: str, f: Fitted) -> bool:
    """Whether a constant freed beyond the tolerance, or an effect added (``f``, nested over ``current``) wins a
    held-out likelihood-ratio test (:func:`ratio_z`) in the TORQUE equation, if its column enters it: the held-out
    squared error falls beyond the one-sided :data:`BLOCK_ALPHA` normal quantile, by :data:`BLOCK_FALL` of its RMS
    at least, the blocks agreeing in sign (:func:`block_t`). The speed view's rows are few and correlated: with four
    to six blocks the block test's Student quantile (3.4-4.5) left a change of a third of the torque error unnamed,
    while the fall's scatter is known from the residual; an effect that cut a 10 kHz log's torque equation by 97 %
    was held to ``sqrt(2 / n_e)`` over one or two independent rows. (Not the armature equation: a current filter
    the torque rows do not show adds ``R t_f i'`` there, L's own column, so its residual is not noise alone.) Only
    a plausible error (within :data:`IMPLAUSIBLE_FACTOR`) is named so; an effect is held to :data:`EFFECT_ALPHA`
    and must be material as well (:func:`is_material`, the caller's)."""
    if implausible_factor(design, f, item) is not None:
        return False
    (t, nb), js = block_t(design, current, f), design.index(item)
    enters = bool(np.any(design.g_train[0, js, js] > 0)) and design.n_test[0] > 0  # eq. dc_mechanical only
    alpha = BLOCK_ALPHA if item in CONSTANTS else EFFECT_ALPHA
    return enters and bool(nb < 2 or t[0] > 0) and f.per_eq[0] <= (1.0 - BLOCK_FALL) * current.per_eq[0] \
        and ratio_z(design, current, f)[0] >= ndtri(1.0 - alpha)


def ratio_z(design: Design, before: Fitted, after: Fitted) -> np.ndarray:
    """Per equation (3,): the held-out squared error's fall from ``before`` to ``after`` (nested) in standard
    errors: with ``d`` the fitted prediction's change on the held-out rows and ``r`` ``after``'s residual there, the
    fall is ``2 r'd + d'd``, and ``r'd`` scatters by ``s sqrt(d'd / q)`` over rows of noise ``s`` independent in a
    fraction ``q`` (:attr:`.regression.Design.independence`); conservative under ``before`` (``2 r'd - d'd``)."""
    dd = sum(_change(design.fold(k), before.folds[k], after.folds[k]) for k in range(design.folds)) \
        if design.folds else _change(design, before, after)
    fall = (before.per_eq ** 2 - after.per_eq ** 2) * design.n_test
    sd = 2.0 * after.per_eq * np.sqrt(np.maximum(dd, 0.0) / np.maximum(design.independence, 1e-12))
    return np.where(sd > 0, fall / np.maximum(sd, 1e-300), 0.0) / math.sqrt(max(design.folds, 1))  # (Design.n_held)


def _change(design: Design, before: Fitted, after: Fitted) -> np.ndarray:
    """(3,) per equation, the squared norm of the fitted prediction's change on the held-out rows."""
    cols = sorted(set(before.cols) | set(after.cols))

    def full(f: Fitted) -> np.ndarray:
        v = np.zeros(len(cols))
        v[[cols.index(j) for j in f.cols]] = f.x
        return v

    d = full(after) - full(before)
    idx = np.array(cols, dtype=int)
    return np.array([float(d @ design.g_test[e][np.ix_(idx, idx)] @ d) for e in range(3)])


def scatter(design: Design) -> float:
    """Two standard errors of a held-out RMS over its independent rows, ``2 / sqrt(2 n)`` (relative), the rows of
    all equations pooled at the torque rows' independence (the fewest): a smaller fall of the score is
    sampling noise (low-passed rows are correlated, :attr:`Design.independence`)."""
    live = design.n_test > 0
    return 2.0 / math.sqrt(2.0 * max(float(design.n_held[live].sum() * design.independence.min()), 1.0))


def beyond_scatter(design: Design, before: Fitted, after: Fitted, items: Sequence[str] = ()) -> bool:
    """Whether ``after``'s held-out fit is better than ``before``'s beyond sampling noise: the score falls by more
    than :func:`scatter`, or one equation's held-out RMS falls by more than two standard errors over ITS
    independent rows (``sqrt(2 / n_e)``): an electrical item need not clear the torque rows' scatter. With the added
    ``items`` given, only an equation they enter counts alone: another one's fall is the shared constants refitted
    (a load torque freeing the motor constant for the armature equation), not theirs."""
    if after.score <= (1.0 - scatter(design)) * before.score:
        return True
    live = (design.n_test > 0) & (before.per_eq > 0) & (equations_of(design, items) if items else True)
    fall = 1.0 - after.per_eq[live] / before.per_eq[live]
    return bool(np.any(fall >= own_scatter(design)[live]))


def block_t(design: Design, before: Fitted, after: Fitted) -> tuple[np.ndarray, int]:
    """Paired comparison over the held-out blocks (:attr:`.regression.Design.g_blocks`): per equation (3,), the
    mean fall of the squared error from ``before`` to ``after`` over the blocks, in standard errors of that mean
    (the blocks' own scatter: whatever the rows' correlation and whatever the residual holds); and the number
    of blocks. Gram-matrix algebra only."""
    nb = design.c_blocks.shape[0]
    if nb < 2:
        return np.zeros(3), nb
    d = np.concatenate([block_falls(design.fold(k), before.folds[k], after.folds[k]) for k in range(design.folds)]) \
        if design.folds else block_falls(design, before, after)
    sd = d.std(axis=0, ddof=1)
    t = np.where(sd > 0, d.mean(axis=0) / np.maximum(sd, 1e-300) * math.sqrt(nb), 0.0)
    return t, nb


def block_falls(design: Design, before: Fitted, after: Fitted) -> np.ndarray:
    """(B, 3) per held-out block and equation, the fall of the squared error from ``before`` to ``after``."""

    def sse(f: Fitted) -> np.ndarray:
        idx = np.array(f.cols, dtype=int)
        g = design.g_blocks[:, :, idx][:, :, :, idx]
        return design.c_blocks - 2 * design.h_blocks[:, :, idx] @ f.x + np.einsum("q,beqr,r->be", f.x, g, f.x)

    return sse(before) - sse(after)


def worst(design: Design, f: Fitted) -> float:
    """The worst-fitting equation's held-out RMS [noise units]: one equation above the noise is enough to go
    on (the combined score averages it with the equations that already fit)."""
    live = design.n_test > 0
    return float(np.max(f.per_eq[live])) if live.any() else math.inf


def implausible_factor(design: Design, f: Fitted, item: str) -> float | None:
    """True / nominal of constant ``item`` in ``f`` where beyond :data:`IMPLAUSIBLE_FACTOR` either way by more than
    :data:`PRIOR_SE` standard errors of its fit (:func:`standard_error`), else None: a B error of exactly half,
    fitted at 0.494 (10020), is within the prior's reach."""
    if item not in CONSTANTS:
        return None
    j = design.index(item)[0]
    factor = 1.0 + f.coefficient(j)
    if max(factor, 1.0 / max(factor, 1e-9)) <= IMPLAUSIBLE_FACTOR:
        return None  # (within the factor: no interval needed; this runs for every challenger of every round)
    se = PRIOR_SE * standard_error(design, f, j)
    near = max(factor - se, 1.0) if factor > 1.0 else min(factor + se, 1.0)  # (the bound nearest nominal)
    return factor if max(near, 1.0 / max(near, 1e-9)) > IMPLAUSIBLE_FACTOR else None


def standard_error(design: Design, f: Fitted, j: int) -> float:
    """Standard error of coefficient ``j`` of ``f`` (a relative error, -): the least-squares covariance
    ``(sum_e q_e G_e / s_e^2)^-1`` over the training Gram matrices ``G_e`` of ``f``'s columns, each equation's rows
    independent in a fraction ``q_e`` (:attr:`.regression.Design.independence`) and scattered by its held-out RMS
    ``s_e`` (noise units, at least 1). Bounds are ignored (the unconstrained curvature)."""
    if j not in f.cols:
        return 0.0
    idx = np.array(f.cols, dtype=int)
    s2 = np.maximum(f.per_eq, 1.0) ** 2
    g = np.einsum("e,eqr->qr", design.independence / s2, design.g_train[:, idx][:, :, idx])
    k = f.cols.index(j)
    d = np.sqrt(np.maximum(np.diag(g), 1e-300))
    cov = np.linalg.pinv(g / np.outer(d, d), rcond=1e-12) / np.outer(d, d)
    return float(math.sqrt(max(cov[k, k], 0.0)))
