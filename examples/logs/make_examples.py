"""Write the example logs of this folder (run from the repository root: ``python examples/logs/make_examples.py``).

Every file is generated from one made-up ROV thruster (``tests/logfiles.py``: a DC-motor equivalent at 16 V
on a bidirectional ESC, reverse thrust coefficient 0.78 of forward), so the answers are known:

* ``thruster_sweep.csv`` / ``.xlsx`` -- a vendor performance sweep, one row per PWM step (title line,
  ``PWM (µs), RPM, Current (A), Voltage (V), Power (W), Force (Kg f), Efficiency (g/W), Force (N)``);
* ``tyto_1585.csv`` -- a Tyto/RCbenchmark 1585 time series (torque cell, optical and electrical RPM, 7 pole pairs);
* ``rig_sweep.mat`` -- the sweep as a MATLAB struct (``sweep.esc_us, sweep.rpm, sweep.thrust_kgf, ...``);
* ``flight_px4.ulg`` -- a PX4 ULog (``esc_status``, ``actuator_motors``; motor 1) without thrust;
* ``flight_ardupilot.bin`` -- an ArduPilot DataFlash log (``ESC``, ``RCOU``; motor 0) without thrust;
* ``thruster.json`` -- the thruster's parameter file (``--params``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from tests.logfiles import (  # noqa: E402
    G0,
    RPM,
    Thruster,
    thruster_sweep,
    tyto_series,
    write_csv,
    write_dataflash,
    write_ulog,
    write_xlsx,
)


def main() -> None:
    th = Thruster()
    sweep = thruster_sweep(th)
    write_csv(sweep, HERE / "thruster_sweep.csv", title="Thruster performance at 16 V (generated example)")
    write_xlsx(sweep, HERE / "thruster_sweep.xlsx", title="Thruster performance at 16 V (generated example)")
    cols, _ = tyto_series("1585")
    write_csv(cols, HERE / "tyto_1585.csv")
    from scipy import io as sio

    pwm = sweep["PWM (µs)"]
    sio.savemat(HERE / "rig_sweep.mat", {"sweep": {"esc_us": pwm, "rpm": sweep["RPM"],
                                                   "thrust_kgf": sweep["Force (N)"] / G0,
                                                   "voltage": sweep["Voltage (V)"], "current": sweep["Current (A)"]}})
    t = 1.0 + np.arange(500) * 0.02
    u = 0.8 * np.sin(2 * np.pi * (t - 1.0) / 5.0)
    w = th.speed(1500 + 400 * u)
    volts = 15.8 - 0.4 * np.abs(u)
    amps = th.supply_power(w) / volts
    write_ulog(HERE / "flight_px4.ulg", t * 1e6, np.abs(w) / RPM, volts, amps, t * 1e6, u, motor=1)
    write_dataflash(HERE / "flight_ardupilot.bin", t * 1e6, np.abs(w) / RPM, volts, amps, t * 1e6,
                    np.round(1500 + 400 * u), instance=0)
    (HERE / "thruster.json").write_text(json.dumps({**th.params(), "name": "example ROV thruster (generated)"},
                                                   indent=2) + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
