"""An item acting on one equation is explained with that equation's held-out fall, not only the round's pooled score
(:func:`ocp.identify.explain.with_fall`), and its figures are the evidence's: the same fit reached two ways, by the
round's history (the sentence) and by refitting the final model without the item (``evidence.*.heldout``)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.identify.diagnosed import blind


@pytest.mark.parametrize(("seed", "item", "equation"), [(3, "thrust_asymmetry", "thrust")])
def test_a_one_equation_items_sentence_quotes_its_equation(seed: int, item: str, equation: str,
                                                           tmp_path: Path) -> None:
    """The blind rig's 3 (``bench/blindrig``: its own integrator and effect formulas): a thrust asymmetry alone."""
    res, truth = blind(seed, tmp_path)
    assert res.verdict == truth["labels"] == [item]
    entry = next(e for r in res.rounds for e in r.entries if e.name == item and e.significant)
    text = entry.explanation
    m = re.search(rf"The {equation} equation's held-out error falls (\d+) % \(([\d.]+) -> ([\d.]+) noise units\)", text)
    assert m is not None, text
    pct, before, after = int(m.group(1)), float(m.group(2)), float(m.group(3))
    without, with_it = res.evidence[item]["heldout"][equation]
    assert (before, after) == (round(without, 2), round(with_it, 2))
    assert pct == round(100 * (1 - with_it / without))
    # the verdict's sentence says it too, then the round's fall of the pooled score, another figure
    sentence = next(s for s in res.explanations if s.startswith(item))
    assert m.group(0) in sentence and f"Held-out error down {100 * entry.improvement:.0f} %" in sentence
    assert round(100 * entry.improvement) != pct
