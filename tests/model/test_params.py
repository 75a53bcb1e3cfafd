import json
import math
from pathlib import Path

import pytest

from ocp.errors import ParameterError
from ocp.model.params import load_params, params_from_mapping

BASE = {"J": 2.71e-5, "B": 5.31e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573, "k_e": 0.0573, "R": 5.0,
        "L": 0.002}


def test_preset_is_si_and_documents_assumptions(rig):
    assert rig.c_f == pytest.approx(1.4e-4)
    text = json.dumps(json.loads(Path("ocp/presets/paper-rig.json").read_text())["notes"])
    assert "assumed" in text and "rad/s" in text


def test_units_block_converts_hz_and_rpm_once():
    hz = params_from_mapping({**BASE, "units": {"c_f": "N/Hz^2", "c_tau": "N*m/Hz^2"}})
    assert hz.c_f == pytest.approx(1.4e-4 / (2 * math.pi) ** 2, rel=1e-12)
    assert hz.c_tau == pytest.approx(2.2e-6 / (2 * math.pi) ** 2, rel=1e-12)
    rpm = params_from_mapping({**BASE, "units": {"c_f": "N/rpm^2"}})
    # thrust at 1000 rpm must not depend on the unit it was given in
    w = 1000 * 2 * math.pi / 60
    assert rpm.c_f * w**2 == pytest.approx(1.4e-4 * 1000**2, rel=1e-12)


@pytest.mark.parametrize(
    ("mutate", "key", "reason"),
    [
        (lambda d: d.pop("R"), "R", "missing"),
        (lambda d: d.update(foo=1.0), "foo", "unknown"),
        (lambda d: d.update(J=-1.0), "J", "greater than 0"),
        (lambda d: d.update(L=0.0), "L", "greater than 0"),
        (lambda d: d.update(c_f=float("nan")), "c_f", "finite"),
        (lambda d: d.update(units={"c_f": "N/furlong^2"}), "units.c_f", "unknown unit"),
        (lambda d: d.update(units={"R": "ohm"}), "units.R", "unknown key"),
    ],
)
def test_bad_parameters_name_the_key(mutate, key, reason):
    d = dict(BASE)
    mutate(d)
    with pytest.raises(ParameterError) as ei:
        params_from_mapping(d)
    assert ei.value.field == key
    assert reason in ei.value.reason


def test_yaml_and_json_files(tmp_path):
    y = tmp_path / "m.yaml"
    y.write_text("\n".join(f"{k}: {v}" for k, v in BASE.items()))
    j = tmp_path / "m.json"
    j.write_text(json.dumps(BASE))
    assert load_params(y) == load_params(j)
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ParameterError, match="not valid JSON"):
        load_params(bad)
    with pytest.raises(ParameterError, match="no preset or file"):
        load_params(tmp_path / "missing.json")


def test_coefficients_match_paper_definitions(rig):
    a1, a2, a3 = rig.current_coefficients
    b1, b2, b3, b4, b5 = rig.voltage_coefficients
    J, B, c, kt, ke, R, L = rig.J, rig.B, rig.c_tau, rig.k_t, rig.k_e, rig.R, rig.L
    assert (a1, a2, a3) == pytest.approx((J / kt, B / kt, c / kt))
    assert (b1, b2, b3, b4, b5) == pytest.approx((L * J / kt, (L * B + R * J) / kt, ke + R * B / kt, R * c / kt,
                                                  2 * L * c / kt))


def test_units_trap_arithmetic(rig):
    """The preset's reading of 'Hz' as rad/s is the one under which the rig reaches its 0.59 N."""
    w_needed = math.sqrt(0.59 / rig.c_f)
    assert rig.max_steady_speed(12.0) > w_needed  # reachable with rad/s
    w_needed_rev = math.sqrt(0.59 / (1.4e-4 / (2 * math.pi) ** 2))
    assert w_needed_rev > 2000 * 2 * math.pi / 60  # out of reach if Hz meant rev/s


def test_both_readings_of_the_papers_hz_are_presets_with_paper_rig_the_rad_s_default(rig):
    revs = load_params("paper-rig-revs")
    assert load_params("paper-rig") == rig and rig.c_f == pytest.approx(1.4e-4)
    assert revs.c_f == pytest.approx(1.4e-4 / (2 * math.pi) ** 2, rel=1e-12)
    assert revs.c_tau == pytest.approx(2.2e-6 / (2 * math.pi) ** 2, rel=1e-12)
    for name in ("paper-rig", "paper-rig-revs"):
        notes = json.loads(Path(f"ocp/presets/{name}.json").read_text())["notes"]
        assert "inconsistent" in notes["units"] and "assumed" in json.dumps(notes)
        assert "2.7 V" not in notes["units"] and "0.49 A" not in notes["units"]  # the circular argument is gone


def test_rotor_evidence_by_hand_arithmetic(rig):
    """C_T, shaft power, momentum-theory power and figure of merit at 0.59 N, recomputed by hand:
    rad/s reading: w = sqrt(0.59 / 1.4e-4) = 64.918 rad/s, n = 10.332 rev/s,
    C_T = 0.59 / (1.225 * 10.332^2 * 0.2^4) = 2.820, P = 2.2e-6 * 64.918^3 = 0.6019 W,
    P_ideal = 0.59^1.5 / sqrt(2 * 1.225 * pi * 0.01) = 0.45319 / 0.27744 = 1.6335 W, FM = 2.714;
    rev/s reading: C_T = 1.4e-4 / (1.225 * 0.2^4) = 0.07143 (independent of the thrust), w = 2 pi 64.918 =
    407.89 rad/s = 3895 r/min, P = (2.2e-6 / (2 pi)^2) * 407.89^3 = 3.782 W, FM = 1.6335 / 3.782 = 0.4319."""
    from ocp.presets.evidence import rotor_evidence

    ev = rotor_evidence(rig)
    assert ev.speed == pytest.approx(64.918, rel=1e-4) and ev.rpm == pytest.approx(619.92, rel=1e-4)
    assert ev.thrust_coefficient == pytest.approx(2.820, rel=1e-3)
    assert ev.shaft_power == pytest.approx(0.6019, rel=1e-3) and ev.ideal_power == pytest.approx(1.6335, rel=1e-4)
    assert ev.figure_of_merit == pytest.approx(2.714, rel=1e-3)
    assert not ev.physical and ev.within_rating and ev.speed_at_voltage > ev.speed
    revs = rotor_evidence(load_params("paper-rig-revs"))
    assert revs.thrust_coefficient == pytest.approx(0.07143, rel=1e-3)
    assert revs.speed == pytest.approx(407.89, rel=1e-4) and revs.rpm == pytest.approx(3895.05, rel=1e-4)
    assert revs.shaft_power == pytest.approx(3.782, rel=1e-3)
    assert revs.figure_of_merit == pytest.approx(0.4319, rel=1e-3)
    assert revs.physical and not revs.within_rating and revs.speed_at_voltage < revs.speed
    assert revs.rated_speed == pytest.approx(2000 * 2 * math.pi / 60)
