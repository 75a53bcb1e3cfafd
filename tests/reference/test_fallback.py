import pytest

from ocp.errors import MissionError
from ocp.reference.analytic import SinProfile
from ocp.reference.fallback import design_sin, sin_peaks
from ocp.theory.reversal import ReversalRegularity


def test_shortest_period_is_tight(rig):
    d = design_sin(rig, 1.0, 8.0, ReversalRegularity.CONTINUOUS_VOLTAGE, amplitude=0.4)
    assert d.profile.q == 2
    assert d.peak_current <= 1.0 and d.peak_voltage <= 8.0
    faster = SinProfile(0.4, d.profile.period * 0.99, 2)
    i, v = sin_peaks(rig, faster)
    assert i > 1.0 or v > 8.0  # 1 % faster breaks a limit


def test_largest_amplitude_is_tight(rig):
    d = design_sin(rig, 0.3, 6.0, ReversalRegularity.C1_VOLTAGE, period=1.0)
    assert d.profile.q == 3
    assert d.peak_current <= 0.3 and d.peak_voltage <= 6.0
    i, v = sin_peaks(rig, SinProfile(d.profile.amplitude * 1.01, 1.0, 3))
    assert i > 0.3 or v > 6.0


def test_unreachable_amplitude_names_field(rig):
    with pytest.raises(MissionError) as ei:
        design_sin(rig, 0.05, 12.0, amplitude=0.5)
    assert ei.value.field == "amplitude"
