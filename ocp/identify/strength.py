"""How sure each name is: the held-out test each item of the verdict passes beside the others (issue #11).

The selection (:mod:`.select`) names an item where its win passes one of several tests (:func:`.evidence.win_test`),
and they are not equally sure. Each item of the final model is tested here by that same function, beside all the other
adopted items (the model without it against the final model), and the test it passes says how it won:

* ``likelihood_ratio``: the torque equation's held-out squared error falls beyond the one-sided normal quantile
  (:func:`.evidence.ratio_agrees`); ``beyond_sampling``: a held-out RMS falls beyond two standard errors over its
  equation's independent rows (:func:`.evidence.beyond_scatter`). Both ``strong``.
* ``held_out_blocks`` (a paired comparison over held-out blocks, :func:`.evidence.blocks_agree`), ``estimate`` (a
  constant's estimate beyond its box, :func:`.evidence.estimate_agrees`), ``ripple_rows`` (an angle ripple's fall
  beyond sampling over the rows independent for a fast ripple, not over the torque rows,
  :func:`.evidence.ripple_beyond`) and ``with_others`` (none of them alone, or an effect no longer material beside
  the others: kept as one of a pair, or as the last effect adopted). All ``weak``.
* ``inductance_timing``: ``L`` beyond sampling noise, weak too. Its only equation is the armature's, where a command
  timing a fraction of a sample off leaves the residual an inductance error leaves, on held-out rows as on training
  rows (the reason :func:`.evidence.estimate_agrees` never names ``L``): sampling noise is not what it must beat.
  Named so, ``L`` was the drawn label 34 times of 39 over the ten proving-ground sets and 3 of 6 on the blind rig
  (session 68's code, before :func:`.inductance.inductance_wins` tried every conventional timing: 35 of 45, 3 of 13).

``input_delay`` is named by the alignment's own tests (:func:`.diagnose._delay_wins`): ``alignment``, strong.
Measured at session 69's code, per name (``python bench/modelcheck.py`` and ``python bench/blind_check.py`` print the
table): over the proving ground's ten sets (2,000 logs) strong names were drawn labels 1,974 times of 2,010, weak ones
56 of 69; over the blind rig's 1,000 logs 919 of 973 and 14 of 34 (a ripple on its own rows 4 of 14). Session 70's
one test for adoption and credit moved no verdict and no credit on those 3,000 logs.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ocp.identify.evidence import equations_of, ratio_z, win_test
from ocp.identify.explain import EQUATIONS, item_name
from ocp.identify.regression import Design
from ocp.identify.select import Fitted, fit_model

#: the tests, surest first, and whether a name won by each is strong (module doc)
STRONG = {"likelihood_ratio": True, "beyond_sampling": True, "alignment": True, "inductance_timing": False,
          "held_out_blocks": False, "estimate": False, "ripple_rows": False, "with_others": False}
#: what each test says, for the answer's text
SAYS = {"likelihood_ratio": "the torque equation's held-out error falls beyond chance (likelihood ratio)",
        "beyond_sampling": "an equation's held-out error falls beyond its sampling noise",
        "alignment": "the command timing's own held-out tests (alignment)",
        "inductance_timing": "only as far as the armature equation's held-out error falls beyond its sampling noise, "
                             "which a command timing a fraction of a sample off moves as an inductance error does "
                             "(the held-out rows share the timing)",
        "held_out_blocks": "only in a paired comparison over held-out blocks, its fall under its equation's "
                           "sampling noise",
        "estimate": "only on its estimate (beyond its box by three standard errors, the held-out blocks agreeing), its "
                    "fall under its equation's sampling noise",
        "ripple_rows": "only over the rows independent for a fast ripple; over the torque rows its fall is within "
                       "sampling noise, where a slow misfit can fit a ripple as well",
        "with_others": "by no test alone beside the other items, only together with them"}


def test_passed(design: Design, without: Fitted, item: str, final: Fitted, min_improvement: float) -> str:
    """The test by which ``final`` beats ``without`` (``final`` less ``item``): the selection's own
    (:func:`.evidence.win_test`, materiality included), ``L``'s fall beyond sampling named ``inductance_timing``, and
    ``with_others`` where none passes alone."""
    test = win_test(design, without, item, final, min_improvement)
    if test is None:
        return "with_others"
    return "inductance_timing" if item == "L" and test == "beyond_sampling" else test


def item_evidence(design: Design, final: Fitted, verdict: list[str], tol: float,
                  min_improvement: float) -> dict[str, dict[str, Any]]:
    """Per verdict name: ``test`` (module doc), ``strong``, ``says`` (the test in words), ``z`` (the torque
    equation's likelihood-ratio z, None where the item does not enter it) and ``heldout`` (per equation it enters,
    the held-out RMS in noise units without it and with it). ``input_delay`` is ``alignment``."""
    out: dict[str, dict[str, Any]] = {}
    if "input_delay" in verdict:
        out["input_delay"] = {"test": "alignment", "strong": True, "says": SAYS["alignment"], "z": None, "heldout": {}}
    for item in final.items:
        if item_name(item) not in verdict:
            continue
        without = fit_model(design, [i for i in final.items if i != item], tol)
        test = test_passed(design, without, item, final, min_improvement)
        enters = equations_of(design, (item,)) & (design.n_test > 0)
        out[item_name(item)] = {
            "test": test, "strong": STRONG[test], "says": SAYS[test],
            "z": float(ratio_z(design, without, final)[0]) if enters[0] else None,
            "heldout": {EQUATIONS[e]: [float(without.per_eq[e]), float(final.per_eq[e])]
                        for e in np.flatnonzero(enters)}}
    return out
