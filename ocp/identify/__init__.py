"""Model check: compare the plant with measurements, find the missing physics, add it, refit.

``check`` (where does the model fail), ``diagnose`` (which effect is missing, ranked by held-out
error reduction), ``fit`` (add named effects, refit, write a calibrated parameter file). Each is a
pure function returning a result object with ``to_dict()`` (JSON-ready, no NaN/inf).

Each equation is checked only where the log has the channels it needs (:mod:`ocp.identify.equations`).
A complete armature time series gets the dynamic check (free run, one-step residuals, every effect a
candidate); steady-state sweeps, ESC rigs (supply-side electrics) and flight logs (no thrust) are checked
point by point and by direction (:mod:`ocp.identify.steady`), where no time effect is ever a candidate.
"""

from ocp.identify.check import CheckOptions, CheckResult, check
from ocp.identify.diagnose import diagnose
from ocp.identify.fit import FitOptions, FitResult, fit
from ocp.identify.result import DiagnoseOptions, DiagnoseResult

__all__ = ["CheckOptions", "CheckResult", "DiagnoseOptions", "DiagnoseResult", "FitOptions", "FitResult", "check",
           "diagnose", "fit"]
