"""The proving ground's plain log columns (:mod:`tests.proving_ground.experiment`: t, voltage, current, thrust, omega
[, theta]) as an ``ocp`` log; kept out of the proving ground, which imports no ``ocp``."""

from __future__ import annotations

import numpy as np

from ocp.logs import Log, log_from_arrays


def rig_log(cols: dict[str, np.ndarray]) -> Log:
    return log_from_arrays(cols["t"], cols["voltage"], cols["current"], cols["thrust"], omega=cols["omega"],
                           theta=cols.get("theta"), source="proving-ground")
