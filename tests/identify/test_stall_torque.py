"""A dry friction or an angle ripple stronger than the motor's stall torque is not named (issue #11: rigs this project
did not build; :func:`ocp.identify.explain.stall_torque`, the effects' ``breakaway``).

Oracles: the closed-form peaks of two-harmonic ripples; the blind rig's own integrator (``bench/blindrig``: its own
physics, written without reading the identifier), whose rotor at rest in a ripple's well stays there when the ripple
peaks just above the stall torque and runs when it peaks just below; the blind rig's fresh seed 352, a clean log on
which a 57-period ripple of 15 N m had been named on a motor of 0.39 N m, and its seed 96, whose right ripple (beside a
wrong ``R``) is still named.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.explain import stall_torque
from ocp.logs import read_log
from ocp.model.effects import load_plant, make_effect
from ocp.model.params import load_params
from ocp.model.stateful_effects import Cogging

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from blindrig.case import generate
from blindrig.draw import draw_case
from blindrig.rig import Rig


@pytest.mark.parametrize(("values", "peak"), [
    ({"tau_sin": 0.3, "tau_cos": 0.4}, 0.5),  # one harmonic: its amplitude either way
    ({"tau_sin": 1.0, "tau_sin2": 0.5}, 3.0 * math.sqrt(3.0) / 4.0),  # odd: +-(sin + sin 2x / 2) at x = pi / 3
    ({"tau_sin": 1.0, "tau_cos2": 0.5}, 0.75),  # peaks 0.75 (sin x = 1/2) and -1.5 (x = -pi/2): the smaller holds
])
def test_a_ripple_holds_a_rotor_with_its_smaller_peak(values: dict[str, float], peak: float) -> None:
    assert make_effect("cogging", {**values, "periods": 7.0}).breakaway() == pytest.approx(peak, rel=1e-4)


def test_dry_friction_holds_with_its_level_and_other_effects_hold_nothing() -> None:
    assert abs(make_effect("coulomb_friction", {"tau_c": -0.02, "omega_eps": 1.0}).breakaway()) == 0.02
    assert make_effect("stribeck", {"tau_s": 0.03, "omega_s": 5.0, "delta": 2.0}).breakaway() == 0.03
    assert make_effect("thrust_lag", {"tau": 0.1}).breakaway() == 0.0


@pytest.mark.parametrize("seed", [12, 95])
def test_the_stall_torque_is_where_a_ripple_stops_holding_the_rotor(seed: int) -> None:
    """On the blind rig's motor ``seed`` under a constant full command, its current settled at rest (``V / R``): a
    6-period ripple peaking 5 % above :func:`stall_torque` holds the rotor at rest in its well (the tilted washboard's
    stable point, ``sin(6 theta) = stall / peak``); one peaking 5 % below has no such point, and the rotor runs from
    the same angle. (The well is shallow this close to the stall torque: a rotor started with no current falls back
    into it and, lightly damped, may leave it; the rule's claim is for a rotor come to rest.)"""
    case = draw_case(seed)
    truth = dataclasses.replace(case.truth, tau_coulomb=0.0, tau_stribeck=0.0, V_brush=0.0, deadband=0.0, delay=0.0)
    volts = truth.V_supply
    stall = stall_torque(load_params(case.nominal).model_copy(update={"k_t": truth.k, "k_e": truth.k, "R": truth.R}),
                         np.array([0.5 * volts, -volts]))
    well = math.asin(1.0 / 1.05) / 6.0  # [rad]
    moved = {}
    for share in (1.05, 0.95):
        rig = Rig(dataclasses.replace(truth, cog_amp=share * stall, cog_N=6, cog_p1=0.0, cog_a2=0.0),
                  h_max=min(1e-5, case.h_max), max_sub=256, theta0=well)
        rig.i = volts / truth.R  # [A] (at rest, settled)
        for _ in range(100):
            rig.advance(volts, 0.005)
        moved[share] = (rig.th - well) / (2.0 * math.pi / 6.0)  # [ripple periods]
    assert abs(moved[1.05]) < 0.05 and moved[0.95] > 10.0, moved


def test_a_ripple_beyond_the_stall_torque_is_not_named_on_a_clean_log(tmp_path: Path) -> None:
    """Blind 352: a clean 500 Hz log of steps whose rotor reverses; a 57-period ripple of 15 N m with a 56 N m
    harmonic fitted the torque equation's rows (the current clipped at reversals) and was named."""
    csv, params, _ = generate(352, tmp_path)
    plant = load_plant(params)
    log = read_log(csv)
    d = diagnose(plant, log)
    assert d.verdict == [], d.verdict
    ap = d.angle_periodic
    assert ap is not None and ap["amplitude"] > stall_torque(plant.params, log.voltage)
    assert "stall torque" in ap["unnamed"]


def test_a_right_ripple_is_named_well_within_the_stall_torque(tmp_path: Path) -> None:
    csv, params, _ = generate(96, tmp_path)
    plant = load_plant(params)
    log = read_log(csv)
    d = diagnose(plant, log)
    assert sorted(d.verdict) == ["cogging", "param:R"], d.verdict
    cog = next(e for e in d.plant.effects if e.name == "cogging")
    assert isinstance(cog, Cogging)
    assert cog.breakaway() < 0.1 * stall_torque(plant.params, log.voltage)
