"""A gain on the command against the constants and drops it mimics (issue #11, item 3: competing explanations).

A gain ``a`` on the armature voltage the motor gets (a driver's scale, a supply sag, a logged command that is not
the terminal voltage) is, in eq. dc_electrical, ``R i + L i' + k w = a V``: dividing by ``a``, ``R``, ``L`` and ``k``
are all ``1/a`` times nominal, and with ``k`` the torque balance of eq. dc_mechanical keeps only if ``J``, ``B`` and
``c_tau`` are too (it scales as a whole); ``c_f`` (eq. thrust) is untouched. So a common relative error ``x`` of
:data:`.coverage.COMMON` is exactly that gain, ``a = 1 / (1 + x)``, on any log. Under a command of one voltage
magnitude (two levels, a PRBS: :func:`.coverage.coverage`, ``voltage_range``) a voltage dead band's ``V0 - v_db``
and a brush drop's ``V0 - v_b`` act as such a gain too (their columns are not offered there,
:func:`.drops.drop_columns`); over several magnitudes a scaled command is fitted by a drop beside ``R`` or ``k``.

The selection does not offer the gain. Where the verdict names some of these constants or drops,
:func:`gain_rival` fits the alternative on the same held-out rows: the verdict's other items and one common relative
error of all six (one column, the sum of their columns in :func:`.columns.constant_columns`, beside their own
calibration within the tolerance). It is reported where it fits as well as the verdict (within the selection's
ambiguity margin or the score's sampling scatter) or better, and the common error is itself beyond the tolerance (a
common error within it is calibration). No excitation tells a gain from a common error of the constants; a measured
terminal voltage does, and a command of several voltage magnitudes tells a dead band or a brush drop from either.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from ocp.identify.columns import DROPS, Column
from ocp.identify.coverage import COMMON, COMMON_GAIN
from ocp.identify.evidence import Fitted, scatter
from ocp.identify.regression import Design
from ocp.identify.select import fit_model


def with_gain(design: Design) -> Design:
    """``design`` with one more column, :data:`.coverage.COMMON_GAIN`: the sum of the columns of :data:`COMMON`
    (relative errors, each column the residual an error of 1 leaves), its Gram entries formed from theirs
    (training, held-out, per block and per fold). Returns a new design; ``design`` is not changed."""
    u = np.zeros(len(design.columns))
    for c in COMMON:
        u[design.index(c)] = 1.0

    def grown(g: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # (..., Q, Q), (..., Q)
        if g.shape[-1] != u.size:  # (no folds: their empty placeholders)
            return g, h
        gu = g @ u
        top = np.concatenate([g, gu[..., :, None]], axis=-1)
        bottom = np.concatenate([gu, (gu @ u)[..., None]], axis=-1)[..., None, :]
        return np.concatenate([top, bottom], axis=-2), np.concatenate([h, (h @ u)[..., None]], axis=-1)

    g_tr, h_tr = grown(design.g_train, design.h_train)
    g_te, h_te = grown(design.g_test, design.h_test)
    g_b, h_b = grown(design.g_blocks, design.h_blocks)
    g_f, h_f = grown(design.g_fold, design.h_fold)
    return replace(design, columns=[*design.columns, Column(COMMON_GAIN, "x")], g_train=g_tr, h_train=h_tr,
                   g_test=g_te, h_test=h_te, g_blocks=g_b, h_blocks=h_b, g_fold=g_f, h_fold=h_f)


def common_error(grown: Design, f: Fitted) -> float:
    """The common relative error of :data:`COMMON` in ``f`` (fitted on ``grown``, :func:`with_gain`): the median of
    their total errors, the common column's coefficient plus each one's own (the split between the two is free
    within the tolerance; the totals are what the log resolves), over the constants the log resolves."""
    g = f.coefficient(grown.index(COMMON_GAIN)[0])
    return float(np.median([g + f.coefficient(j) for c in COMMON if c not in grown.unresolved
                            for j in grown.index(c)]))


def gain_rival(design: Design, best: Fitted, tol: float, margin: float, one_magnitude: bool) -> dict[str, Any] | None:
    """The ambiguity (module doc) where what ``best`` (fitted on ``design``) names of :data:`COMMON` and of the
    voltage drops (:data:`.columns.DROPS`, a gain on a command of one magnitude; named on a scaled command of
    several, where no gain was on offer) is one gain on the command: the alternative replaces them all by it (kept
    beside it, a drop took up the gain with the opposite sign: proving-ground rig 126, a 19 % scale reported as a
    -38 % error). Returns ``adopted`` (the items it replaces, joined by ``+``),
    ``alternative`` (:data:`.coverage.COMMON_GAIN`), both scores [noise units], the common relative error
    ``relative`` (:func:`common_error`), the ``gain`` and the ``reason``; None where the verdict names none of them,
    the gain fits worse (beyond ``margin`` or the score's sampling scatter), or it is within ``tol``.
    ``one_magnitude``: the command holds one voltage magnitude (the reason then names the dead band and the brush
    drop)."""
    named = [i for i in best.items if i in COMMON]
    drops = [i for i in best.items if i in DROPS]
    if not named + drops:
        return None
    grown = with_gain(design)
    out = named + drops
    alt = fit_model(grown, [*(i for i in best.items if i not in out), COMMON_GAIN], tol)
    x = common_error(grown, alt)
    tie = max(margin, scatter(design))
    if alt.score > best.score * (1.0 + tie) or abs(x) <= tol:
        return None
    names = " + ".join(f"param:{i}" if i in COMMON else i for i in out)
    how = "better than" if alt.score * (1.0 + tie) < best.score else f"as well as (within {100 * tie:.1f} %)"
    causes = ("on this command of one voltage magnitude a voltage dead band or a brush drop acts as that gain (a "
              "command of several magnitudes tells them apart: design-experiment proposes one); else "
              if one_magnitude else "")
    return {"adopted": names, "alternative": COMMON_GAIN, "score": best.score, "alternative_score": alt.score,
            "relative": x, "gain": 1.0 / (1.0 + x),
            "reason": f"one common error of R, L, k, J, B and c_tau ({100 * x:+.1f} %), which is a gain of "
                      f"{1.0 / (1.0 + x):.3g} on the logged command, fits the held-out data {how} {names} "
                      f"({alt.score:.3g} vs {best.score:.3g} noise units): {causes}the logged voltage may not be "
                      "the motor's (a drive's gain, a supply sag); no excitation tells such a gain from a common "
                      "error of these constants, a measured terminal voltage does"}
