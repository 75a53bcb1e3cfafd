"""diagnose: which physics is missing? Explanations compete on HELD-OUT evidence.

Procedure:

1. **Conventions** (:mod:`.signs`, :mod:`.align`): a channel logged with the opposite sign is refused, named; the
   command-to-sensor lag is estimated and removed; only a lag beyond what logging conventions explain (stated rule
   there) is called ``input_delay``, and only when it predicts the held-out speed and current better (by
   ``min_improvement``) than the best lag within them, or halves the alignment search's own residual (the armature
   equation with free coefficients, which wrong constants do not swamp), or predicts the armature's held-out
   current better from the logged speed.
2. Split the log into segments of ``segment_s`` seconds; every ``holdout_every``-th is held out (sweeps: rows).
   Competing models are scored by cross-validation (``cross_validate``): each class of segments held out in turn,
   the model fitted on the others (every row held out once: evidence at one slow reversal counts where it falls).
3. **Regression** (:mod:`.regression`): the nominal model's equation residuals against the columns of every
   candidate -- catalogue effects (shaped ones on a grid; angle-periodic torque with its period count from the
   residual's spectrum against rotor angle) and relative errors of the constants.
4. **Selection** (:mod:`.select`): every model refines all constants within ``tolerance`` of nominal
   (``calibration``); a constant is *named* (``param:<key>`` in the verdict) only when freeing it beyond
   the tolerance wins on held-out data: forward selection while the held-out score is above ``noise_floor``
   and falls beyond sampling noise (an effect: also by ``min_improvement``; a constant's materiality is the
   tolerance). Adopted items that another item, or named constants that one gain on the command (:mod:`.gain`),
   explain equally well (within ``ambiguity_margin``) are reported under ``ambiguous`` with the reason.
5. The user's plant and each round's adopted model are free-run (:func:`ocp.identify.predict.free_run`) on the
   held-out segments: the per-channel errors reported. ``verdict``: adopted effects and named constants, by rank.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable

import numpy as np

from ocp.errors import SolverError
from ocp.identify.align import (
    DELAY_GAIN,
    SKEW_FRACTION,
    Alignment,
    armature_error,
    estimate,
    gain,
    spread,
    within,
)
from ocp.identify.candidates import candidate
from ocp.identify.coverage import blind_spots, coverage, unseen_rivals
from ocp.identify.evidence import IMPLAUSIBLE_FACTOR, Fitted, implausible_factor
from ocp.identify.explain import (
    KEYS,
    calibration,
    explain,
    item_name,
    item_values,
    physical,
    plant_of,
    spectrum_peak,
    stall_torque,
    units,
    verdict_sentence,
    with_fall,
)
from ocp.identify.gain import gain_rival
from ocp.identify.holdout import Split, split
from ocp.identify.inductance import (
    FILTER_MIMICS,
    TIMING_MIMICS,
    delay_rival,
    filter_headroom,
    filter_mimics,
    inductance_wins,
    open_timing,
    timed_inductance,
)
from ocp.identify.predict import CHANNELS, free_run, noise_levels, read_current
from ocp.identify.realign import applying, realign
from ocp.identify.regression import CONSTANTS, REGRESSED, Design, build
from ocp.identify.replica import unmasked
from ocp.identify.result import DiagnoseOptions, DiagnoseResult, RankEntry, Round, Score
from ocp.identify.select import Selection, select
from ocp.identify.signs import check_signs
from ocp.identify.strength import item_evidence
from ocp.logs import Log, LogKind
from ocp.model.effects import make_effect
from ocp.model.plant import DCMotorPlant
from ocp.parallel import own_threads


def dynamic(log: Log) -> bool:
    """Whether the dynamic check (free run under the armature voltage) applies: a complete time series."""
    return log.complete and log.kind is LogKind.TIME_SERIES


def score(plant: DCMotorPlant, log: Log, mask: np.ndarray, noise: dict[str, float], segment_s: float,
          centred: bool = False, sensor: bool = True) -> Score:
    """Free run of ``plant`` over ``log`` in ``segment_s`` segments, its error on the rows ``mask`` (N,) per
    channel (``centred``: about its mean on those rows, a standard deviation: a constant sensor offset left out);
    ``sensor``: the current read through the current sensor's lag fitted on the other rows."""
    fr = free_run(plant, log, segment_s)
    if sensor:
        fr = read_current(fr, log, ~mask)
    keep = mask[fr.idx]
    err = {ch: getattr(log, ch)[fr.idx][keep] - fr.channel(ch)[keep] for ch in CHANNELS}
    rms = {ch: float(np.std(e) if centred else np.sqrt(np.mean(e ** 2))) for ch, e in err.items()}
    comb = math.sqrt(sum((rms[ch] / noise[ch]) ** 2 for ch in CHANNELS) / len(CHANNELS))
    return Score(rms, comb if math.isfinite(comb) else math.inf, fr.current_lag)


def _pool(plant: DCMotorPlant, opt: DiagnoseOptions) -> tuple[tuple[str, ...], list[str]]:
    """Effects to build columns for, and the selection pool (effects + constants) as regression names."""
    present = {e.name for e in plant.effects}
    wanted = opt.candidates
    for n in wanted or ():
        candidate(n)  # unknown names raise, naming them
    effects = tuple(n for n in REGRESSED if n not in present and (wanted is None or n in wanted))
    consts = [c for c in CONSTANTS if opt.include_params and (wanted is None or f"param:{c}" in wanted
                                                               or any(f"param:{k}" in wanted for k in KEYS[c]))]
    return effects, [*effects, *consts]


def _entry(name: str, fit_: Fitted, before: Fitted, significant: bool, plant: DCMotorPlant, design: Design,
           heldout: dict[str, float]) -> RankEntry:
    values = item_values(design, fit_, name, plant.params)
    imp = 1.0 - fit_.score / before.score if before.score > 0 else 0.0
    text = with_fall(explain(name, values, plant.params, design, fit_), design, before, fit_, name)
    return RankEntry(item_name(name), imp, significant, values, units(name), heldout, text)


def timing(plant: DCMotorPlant, log: Log) -> tuple[float, tuple[float, float]]:
    """What the alignment needs of ``plant``: the delay it applies itself (its ``input_delay``) [samples of ``log``]
    and its nominal armature ``(L/R [s], k_e [V s/rad])``."""
    own = sum(float(getattr(e, "delay", 0.0)) for e in plant.effects if e.name == "input_delay") / log.dt
    return own, (plant.params.L / plant.params.R, plant.params.k_e)


def aligned(plant: DCMotorPlant, log: Log, max_logging_skew: float) -> tuple[Alignment, Log]:
    """``log`` realigned by the lag logging conventions explain, for confronting ``plant`` with it (``check``,
    ``fit``), and that alignment: estimated as :func:`diagnose` does, held within the conventions (:func:`.within`: a
    longer lag is an ``input_delay``, which only :func:`diagnose` names), less the delay ``plant`` applies itself. A
    steady-state sweep is returned as it is. A channel logged with the opposite sign is refused (:mod:`.signs`)."""
    if log.kind is not LogKind.TIME_SERIES:
        return estimate(log), log
    check_signs(plant, log)
    own, armature = timing(plant, log)
    align = estimate(log, max_logging_skew + own, armature)
    if align.delay:
        align = within(align, max_logging_skew + own, log.dt)
    return applying(align, log, own, armature[0] / log.dt, max_logging_skew)


@own_threads
def diagnose(plant: DCMotorPlant, log: Log, options: DiagnoseOptions | None = None,
             progress: Callable[[float], None] | None = None) -> DiagnoseResult:
    """Say which effects are missing and which constants are wrong (module doc). ``progress(fraction)``
    is called as the work advances (for progress bars). Independent pieces run in threads, BLAS in one
    (:func:`ocp.parallel.own_threads`)."""
    opt = options or DiagnoseOptions()
    if not dynamic(log):  # sweeps, ESC rigs and flight logs: point by point, never a time effect (issue #13)
        from ocp.identify.steady_diagnose import diagnose_points

        return diagnose_points(plant, log, opt)
    effects, pool = _pool(plant, opt)
    check_signs(plant, log)
    own, armature = timing(plant, log)
    align = estimate(log, opt.max_logging_skew + own if log.kind is LogKind.TIME_SERIES else 0.0, armature)
    seg = min(opt.segment_s, log.n * log.dt / (3 * opt.holdout_every)) if log.kind is LogKind.TIME_SERIES \
        else opt.segment_s  # short logs: shorter segments, so that some are held out
    sp = split(log, seg, opt.holdout_every, opt.cross_validate)
    noise = noise_levels(log)
    tau = armature[0] / log.dt  # the nominal L/R [samples]: how the armature shows a fraction of a sample
    current = functools.cache(lambda lag: armature_error(log, lag, tau, sp.train, sp.test))  # (per lag, once)
    unconfirmed = None  # (a lag beyond the conventions that predicts no better: not a delay)
    if align.delay and "input_delay" in _allowed(opt) and not _delay_wins(plant, log, align, own, opt, sp, noise, seg,
                                                                            current):
        unconfirmed, align = align, within(align, opt.max_logging_skew + own, log.dt)
    delay = (align.samples - own) * log.dt if align.delay and "input_delay" in _allowed(opt) else None
    top = math.inf if delay is not None else opt.max_logging_skew  # (a conventions' lag: at most its whole samples)
    align, aligned = applying(align, log, own, tau, top)  # the equations always see the command when it acts
    work = log if delay is not None else aligned  # free runs: the delay, if called, is in the plant
    held = (log.voltage, align.applied or 0.0)  # (the drive's dead band acts before the shift)

    def judged(design: Design, f: Fitted) -> str | None:  # why a named L is not (what mimics it, on free runs)
        final, shift = plant_of(plant, design, f, delay), None if delay is not None else align.samples - own
        error = functools.partial(_free_error, sp=sp, noise=noise, seg=seg)
        if "L" in design.one_sided and filter_mimics(plant, final, log, shift, tau, opt.max_logging_skew,
                                                     functools.partial(error, channels=("omega",))):
            return FILTER_MIMICS  # (first: the filter is the specific cause; the timing below mimics it too)
        if not inductance_wins(plant, final, f.items, log, shift, tau, error, opt.min_improvement,
                               opt.max_logging_skew, searched=unconfirmed is None):
            return TIMING_MIMICS
        return None

    stall = stall_torque(plant.params, log.voltage)
    design, sel, aside = _explain(plant, aligned, sp, effects, pool, noise, opt, delay is not None, progress, align,
                                  held, judged, stall)
    base = score(plant, work, sp.test, noise, seg)
    rounds, verdict, explanations = [], [], []
    if delay is not None:
        with_delay = DCMotorPlant(plant.params, (*plant.effects, make_effect("input_delay", {"delay": delay})))
        before, base = base, score(with_delay, work, sp.test, noise, seg)
        text = (f"input_delay: the command acts {1e3 * delay:.3g} ms ({align.samples:.2f} samples) after its row, "
                f"beyond the {opt.max_logging_skew:g}-sample logging skew. {align.rule}.")
        rounds.append(Round(before, [RankEntry("input_delay", 1.0 - base.combined / before.combined, True,
                                               {"delay": delay}, {"delay": "s"}, base.rms, text)]))
        verdict.append("input_delay")
        explanations.append(text)
    for step in sel.steps:
        before = base
        heldout: dict[str, float] = {}
        if step.adopted is not None:
            try:
                base = score(plant_of(plant, design, step.tried[0][1], delay), work, sp.test, noise, seg)
                heldout = base.rms
            except SolverError:  # a plant too stiff to free-run: no held-out figure (free_run says why)
                pass
        entries = [_entry(n, f, step.before, n == step.adopted, plant, design, heldout if n == step.adopted else {})
                   for n, f in step.tried]
        rounds.append(Round(before, entries))
        if step.adopted is not None:
            verdict.append(item_name(step.adopted))
            explanations.append(verdict_sentence(step.adopted, step.tried[0][1], step.before, sel.final,
                                                 plant.params, design))
    for c in sel.dropped:  # (named in a forward step, no longer needed beside the others: not named)
        k = verdict.index(item_name(c))
        del verdict[k]
        explanations[k] = (f"{item_name(c)} is not named: adopted in an early round, it no longer wins on held-out "
                           f"data beside {', '.join(verdict) or 'nothing'}"
                           + (" (calibrated instead)" if c in CONSTANTS else ""))
        explanations.append(explanations.pop(k))
    if progress is not None:
        progress(1.0)
    final = plant_of(plant, design, sel.final, delay)
    ambiguous = [{**a, "adopted": item_name(str(a["adopted"])), "alternative": item_name(str(a["alternative"]))}
                 for a in sel.ambiguous]
    rival = delay_rival(current, unconfirmed.samples, align.samples, noise["current"], opt.ambiguity_margin) \
        if unconfirmed is not None and "param:L" in verdict else None
    cov = coverage(log)  # (read by the gain's reason and the blind spots)
    gain = gain_rival(design, sel.final, opt.tolerance, opt.ambiguity_margin, not cov["voltage_range"])
    ambiguous += [r for r in (rival, gain) if r] + unseen_rivals(design.unseen, verdict, sel.final.score)
    return DiagnoseResult(verdict, rounds, final, noise, explanations + aside, align,
                          calibration(plant.params, design, sel.final, opt.tolerance), ambiguous,
                          spectrum_peak(design, stall, sel.ripple), opt.tolerance,
                          blind_spots(log, verdict, gain=gain is not None, cov=cov),
                          item_evidence(design, sel.final, verdict, opt.tolerance, opt.min_improvement))


def _explain(plant: DCMotorPlant, log: Log, sp: Split, effects: tuple[str, ...], pool: list[str],
             noise: dict[str, float], opt: DiagnoseOptions, delayed: bool,
             progress: Callable[[float], None] | None, align: Alignment,
             held: tuple[np.ndarray, float] | None = None, judged: Callable[[Design, Fitted], str | None] | None = None,
             stall: float = math.inf) -> tuple[Design, Selection, list[str]]:
    """Regression and selection; where an angle is logged, the torque equation on the raw rows (a torque
    ripple faster than the low-pass kept, :mod:`.regression`). Where the alignment is not identified (flat
    search residual) or was found only with the nominal armature (:attr:`.align.Alignment.nominal`: it assumed
    ``L``), ``L`` is judged beside the timing error it cannot be told from (:func:`.inductance.open_timing`).
    A measured one: ``L`` named only where ``judged`` gives no reason against it (:func:`.inductance.inductance_wins`,
    :func:`.inductance.filter_mimics`); else it is unresolved, or free above nominal again, the selection redone. No
    model is adopted with a dry friction or a ripple beyond ``stall`` [N m] (:func:`.explain.stall_torque`), nor an
    effect that takes as much of the nominal plant's noise-free replica of the log (:func:`.replica.unmasked`)."""
    design = build(plant.params, log, sp.train, sp.test, effects, noise, raw_torque=True, held=held,
                   folds=list(sp.folds) or None)
    if log.kind is LogKind.TIME_SERIES:
        if not align.identified or align.nominal:  # (a lag found with the nominal armature assumed L)
            open_timing(design, plant, log, opt.tolerance, opt.max_logging_skew)
        elif "L" in design.unresolved:
            timed_inductance(design, plant, log, opt.tolerance, spread(align))
        filter_headroom(design, plant, log)
    if progress is not None:
        progress(0.2)
    redo = functools.partial(select, design, tol=opt.tolerance, min_improvement=opt.min_improvement,
                             noise_floor=opt.noise_floor, max_items=opt.max_effects - delayed,
                             margin=opt.ambiguity_margin, physical=functools.partial(physical, design, stall=stall))
    sel = redo(pool, progress=None if progress is None else (lambda f: progress(0.2 + 0.6 * f)))
    why = None
    if "L" in sel.final.items and implausible_factor(design, sel.final, "L") is not None:
        # beyond a factor two: a timing error (an unconfirmed delay under an open timing; a command skew or a current
        # filter the alignment did not take) is the likelier explanation (the prior of .select; blind 357)
        why = ("the command timing is not identifiable in this log (flat alignment residual) and " if not
               align.identified else "L/R is under two samples and " if "L" in design.slack else "") + \
              ("L would have to be off by more than a factor two: a timing error of the command or of the current's "
               "sensor explains the armature equation as well")
    elif judged is not None and "L" in sel.final.items:
        why = judged(design, sel.final)
    if why == FILTER_MIMICS:  # free above nominal, as a filter may raise it; the selection redone
        design.above["L"], design.one_sided["L"] = math.inf, why
    elif why is not None:  # L is unresolved, the selection redone
        for box in (design.slack, design.above, design.one_sided):
            box.pop("L", None)
        design.unresolved["L"] = why
    if why is not None:
        sel = redo(pool)
    return (design, *unmasked(plant, log, design, sel, pool, redo, opt.tolerance, opt.min_improvement, sp))


def _delay_wins(plant: DCMotorPlant, log: Log, align: Alignment, own: float, opt: DiagnoseOptions, sp: Split,
                noise: dict[str, float], seg: float, current: Callable[[float], float] | None = None) -> bool:
    """Whether a lag beyond the logging conventions predicts the held-out current (what the armature voltage
    drives first; free run, in noise units) better by the selection's ``min_improvement``
    than the best lag within them (its fraction of a sample taken as the equations take it, the drive switching
    within the row, :func:`.realign.switched`; the longer lag's delay of the held command switches so too), or cuts
    the alignment search's residual by :data:`.align.DELAY_GAIN` (the armature equation with free coefficients,
    which other model errors do not swamp, :func:`.align.gain`), or predicts the held-out current of the armature
    alone better by ``min_improvement`` (:func:`.align.armature_error`, or ``current``: that error per lag [samples]
    of ``log``; driven by the logged speed, each lag with its own best L/R, so a wrong inertia or a missing load does
    not swamp it, and a longer L/R gets its chance to mimic the delay): only then is it an ``input_delay``. (Added
    in session 35: on 800 proving-ground logs, 15 lags beyond the conventions failed the first two tests; the
    armature's held-out error fell 17-89 % for three of the five true delays among them, 8 % and 0 % for the other
    two, and rose 9 % or more for the ten without one.) The free runs'
    errors are taken about their held-out means: a sensor's constant offset, which every timing shares, decides
    nothing (a current offset of 26 noise units hid a 6.4-sample delay, proving-ground seed 9392). A lag measured
    with a slow armature's nominal L/R held (:attr:`.align.Alignment.bias`) must also beat that L/R made as much
    longer as puts the lag at the conventions' edge (within the factor-two prior, :data:`IMPLAUSIBLE_FACTOR`): on a
    smooth command the two look alike, and only held-out data tell an inductance error from a delay. (Not the speed,
    since session 72: a speed sensor's lag, which no shift of the command removes, is matched by a delayed command's
    late simulated speed; blind rig 800, 249: false delays, the current against them. Model-check history.)"""
    if gain(align, opt.max_logging_skew + own) >= DELAY_GAIN:
        return True
    short = within(align, opt.max_logging_skew + own, log.dt).samples - own
    tau = timing(plant, log)[1][0] / log.dt
    current = current or (lambda lag: armature_error(log, lag, tau, sp.train, sp.test))
    if current(align.samples) <= (1.0 - opt.min_improvement) * current(short + own):
        return True
    lag = make_effect("input_delay", {"delay": (align.samples - own) * log.dt})
    rivals = [(plant, realign(log, short, tau, opt.max_logging_skew))]
    edge = opt.max_logging_skew + SKEW_FRACTION
    longer = 1.0 + (align.samples - own - edge) / tau  # the L/R, x nominal, that puts the lag at the edge
    if align.bias and longer <= IMPLAUSIBLE_FACTOR:  # (a held slow armature: the same lag as a longer L/R)
        rivals.append((DCMotorPlant(plant.params.model_copy(update={"L": longer * plant.params.L}), plant.effects),
                       realign(log, edge, longer * tau, opt.max_logging_skew)))
    delayed, *conv = (_free_error(p, x, sp, noise, seg, channels=("current",)) for p, x in
                      ((DCMotorPlant(plant.params, (*plant.effects, lag)), log), *rivals))
    return delayed <= (1.0 - opt.min_improvement) * min(conv)


def _free_error(p: DCMotorPlant, x: Log, sp: Split, noise: dict[str, float], seg: float,
                channels: tuple[str, ...] = ("omega", "current")) -> float:
    """Held-out free-run error of ``p`` on ``x`` in speed and current (``channels``), noise units, about their
    held-out means (a sensor's constant offset, which every timing shares, decides nothing): what a timing rival
    is judged by."""
    e = score(p, x, sp.test, noise, seg, centred=True, sensor=False).rms
    return math.hypot(*(e[c] / noise[c] for c in channels))


def _allowed(opt: DiagnoseOptions) -> set[str]:
    return set(opt.candidates) if opt.candidates is not None else {"input_delay"}
