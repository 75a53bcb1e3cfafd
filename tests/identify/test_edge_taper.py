"""The torque rows next to the log's cut edges are tapered in before the speed view (issue #11, session 9).

Proving-ground tuning draw ``make_case(1289)`` (a tuning seed, not one of the reported 0..199): a 0.6 s, 10 kHz log
of a rig with a thrust asymmetry and a 1024-count encoder, its constants right; the rotor time constant (0.1 s) is
a sixth of the log. Cut off hard at the edge rows, the speed view's ``J w'`` held the speed of the one row at each
cut (steps of 61 rad/s between rows), a slow torque error of ~40 noise units over the whole log that a ``J`` 18 %
low explained in part: ``param:J`` was named beside the asymmetry. Tapered over a rotor time constant, the torque
equation is at its noise and only the asymmetry is named.
"""

from __future__ import annotations

import numpy as np

from ocp.identify import diagnose
from ocp.identify.regression import edge_taper
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_a_coarse_encoder_at_10_khz_names_no_inertia() -> None:
    case = make_case(1289)
    assert case.expected == {"thrust_asymmetry"} and not case.constant_error and case.logger.rate == 10000.0
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert res.verdict == ["thrust_asymmetry"]


def test_edge_taper_shape() -> None:
    edge = np.zeros(100, dtype=bool)
    edge[:5] = edge[-5:] = True
    w = edge_taper(edge, 10.0)
    assert np.all(w[edge] == 0.0) and np.all(w[15:85] == 1.0)
    assert np.all(np.diff(w[4:16]) > 0) and np.all(np.diff(w[84:96]) < 0)  # rising in, falling out
    assert np.allclose(w[5:15], w[94:84:-1])  # symmetric
    assert np.all(edge_taper(edge, 1.0)[~edge] == 1.0)  # under two rows: no taper
    assert np.all(edge_taper(edge, 1e6)[20:80] == 1.0)  # at most a sixth of the rows inside


def test_the_rows_beside_a_cut_inside_the_log_are_tapered_too() -> None:
    """Rows cut inside the log (where the rotor is held, :func:`ocp.identify.columns.held_still`) are cut ends too:
    each run of rows between cuts rises and falls over the same ramp, at most a sixth of that run."""
    edge = np.zeros(200, dtype=bool)
    edge[:5] = edge[-5:] = edge[100:110] = True
    w = edge_taper(edge, 10.0)
    assert np.all(w[edge] == 0.0) and np.all(w[15:90] == 1.0) and np.all(w[120:185] == 1.0)
    assert np.allclose(w[90:100], w[5:15][::-1]) and np.allclose(w[110:120], w[5:15])  # the ends' own ramp
    short = edge.copy()
    short[20:190] = True  # a run of 15 rows (5..19): a ramp of at most 2 rows each way
    assert np.count_nonzero(edge_taper(short, 10.0)[5:20] < 1.0) == 4
