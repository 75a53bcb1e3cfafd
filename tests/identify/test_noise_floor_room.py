"""The noise floor (``DiagnoseOptions.noise_floor``): forward selection goes on while some equation's held-out RMS
is above it (1: the noise level itself). An effect then wins in whichever equation it enters: a noise level is an
estimate, and an effect's material fall below it shows that it was too high (until session 12, effects too were
held to the equations above the floor, and a 10 kHz log's angle ripple cutting its torque equation from 0.86 to
0.25 noise units was never named); a constant, named without a material fall, only in an equation above it, or
one whose held-out RMS it halves (``select.ROOM_FALL``, session 22: noise cannot lose half its error to one constant).
With every equation within the floor the search stops, but for an effect that halves one it enters (session 50).
Hand-made regressions (rows independent, residuals in noise units, 4000 rows a third held out)."""

from __future__ import annotations

import numpy as np

from ocp.identify import DiagnoseOptions
from ocp.identify.regression import Column, Design
from ocp.identify.select import ROOM_FALL, _room, fit_model, select

EFFECT = "force_offset"


def _design(eq: int, signal: float, noise: float, other: float, seed: int = 5, item: str = EFFECT) -> Design:
    """Equation ``eq``'s residual ``signal x + noise e``, explained by ``item``'s column ``x``; the thrust equation
    (2, unless ``eq`` is 2) unit-free noise of RMS ``other`` that no column explains, beside a right ``c_f``."""
    n = 4000
    rng = np.random.default_rng(seed)
    x, e, u, z = rng.standard_normal((4, n))
    train, test = np.arange(n) % 3 != 0, np.arange(n) % 3 == 0
    g_tr, g_te = np.zeros((3, 2, 2)), np.zeros((3, 2, 2))
    h_tr, h_te, c_tr, c_te = np.zeros((3, 2)), np.zeros((3, 2)), np.zeros(3), np.zeros(3)
    parts = [(eq, np.column_stack([x, 0 * x]), signal * x + noise * e)]
    if eq != 2 and other > 0:
        parts.append((2, np.column_stack([0 * u, u]), other * z))
    for k, cols, y in parts:
        for g, h, c, rows in ((g_tr, h_tr, c_tr, train), (g_te, h_te, c_te, test)):
            g[k], h[k], c[k] = cols[rows].T @ cols[rows], cols[rows].T @ y[rows], y[rows] @ y[rows]
    live = np.array([k in {p[0] for p in parts} for k in range(3)], int)
    return Design([Column(item, "f0" if item == EFFECT else item), Column("c_f", "c_f")], g_tr, g_te, h_tr, h_te,
                  c_tr, c_te, live * int(train.sum()), live * int(test.sum()), np.ones(3))


def _adopted(d: Design, floor: float, item: str = EFFECT) -> tuple[str, ...]:
    return select(d, [item], tol=0.1, min_improvement=0.12, noise_floor=floor, max_items=3, margin=0.02).final.items


def test_an_item_is_adopted_for_an_equation_whose_noise_level_was_overestimated() -> None:
    d = _design(eq=1, signal=0.8, noise=0.45, other=1.5)  # armature at ~0.92 stated noise units, its true noise 0.45
    assert _adopted(d, DiagnoseOptions().noise_floor) == (EFFECT,)


def test_a_constant_is_not_named_for_an_equation_within_the_floor() -> None:
    """A constant needs no material fall (its materiality is the tolerance), so the floor still holds it: the same
    armature residual as above, explained by a resistance error that cuts it by 45 % (under ``ROOM_FALL``), is not
    named beside the thrust equation at 1.5."""
    d = _design(eq=1, signal=0.8, noise=0.45, other=1.5, item="R")
    now, named = fit_model(d, [], 0.1), fit_model(d, ["R"], 0.1)
    assert 0.4 < 1.0 - named.per_eq[1] / now.per_eq[1] < ROOM_FALL
    assert _adopted(d, DiagnoseOptions().noise_floor, "R") == ()
    assert _adopted(d, 0.5, "R") == ("R",)  # (it would win: only the floor stops it)


def test_a_constant_that_halves_an_equation_within_the_floor_is_named() -> None:
    """An armature equation at ~0.85 stated noise units, most of it a resistance error (true noise 0.3): the stated
    noise level was too high, and the constant that cuts the equation by 64 % (over ``ROOM_FALL``) is named."""
    d = _design(eq=1, signal=0.9, noise=0.3, other=1.5, item="R")
    now, named = fit_model(d, [], 0.1), fit_model(d, ["R"], 0.1)
    assert now.per_eq[1] < 1.0 and 1.0 - named.per_eq[1] / now.per_eq[1] > ROOM_FALL
    assert _adopted(d, DiagnoseOptions().noise_floor, "R") == ("R",)


def test_the_search_stops_when_every_equation_is_within_the_floor() -> None:
    d = _design(eq=1, signal=0.5, noise=0.8, other=0.0)  # the armature equation alone, at ~0.94 noise units
    now, fitted = fit_model(d, [], 0.1), fit_model(d, [EFFECT], 0.1)
    assert 0.12 < 1.0 - fitted.per_eq[1] / now.per_eq[1] < ROOM_FALL
    assert _adopted(d, DiagnoseOptions().noise_floor) == ()
    assert _adopted(d, 0.5) == (EFFECT,)  # (it would win: only the floor stops it)


def test_an_effect_that_halves_an_equation_within_the_floor_is_adopted() -> None:
    """With every equation within the floor, an effect still wins where it halves one it enters (as a constant's
    room, session 50): the armature equation alone at ~0.92 stated noise units, its true noise 0.45."""
    d = _design(eq=1, signal=0.8, noise=0.45, other=0.0)
    now, fitted = fit_model(d, [], 0.1), fit_model(d, [EFFECT], 0.1)
    assert now.per_eq[1] < 1.0 and 1.0 - fitted.per_eq[1] / now.per_eq[1] > ROOM_FALL
    assert _adopted(d, DiagnoseOptions().noise_floor) == (EFFECT,)


def test_an_equation_just_above_its_noise_is_still_explained() -> None:
    d = _design(eq=0, signal=0.8, noise=0.75, other=0.0)  # torque at ~1.10 noise units, half of it the effect
    assert _adopted(d, DiagnoseOptions().noise_floor) == (EFFECT,)


def test_a_pair_is_held_to_the_floor_through_its_constants_only() -> None:
    """The rule is one for single items and for pairs (``select._room``, which ``_pair`` shares): an effect needs
    no room, a constant does, and a pair holding a constant needs it for that constant's equations."""
    d = _design(eq=1, signal=0.8, noise=0.45, other=1.5, item="R")  # armature within the floor, thrust above
    now = fit_model(d, [], 0.1)
    assert now.per_eq[1] < 1.0 < now.per_eq[2]
    named = fit_model(d, ["R"], 0.1)  # (cuts the armature equation by 45 %: under ROOM_FALL)
    assert _room(d, now, (EFFECT,), 1.0, now)  # (EFFECT has no column here: an effect is never held)
    assert not _room(d, now, ("R",), 1.0, named)
    assert not _room(d, now, (EFFECT, "R"), 1.0, named)
    assert _room(d, now, ("c_f",), 1.0, now)  # the thrust equation, above the floor
