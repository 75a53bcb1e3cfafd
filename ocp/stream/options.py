"""Options of the streaming shaper: limits, crossing regularity, look-ahead, sample period, bandwidth.

All values SI: current [A], voltage [V], delay [s], dt [s], bandwidth [Hz]. Options are strict (unknown
keys are errors naming the key) and checked once, before any work starts.

The regularity classes are the optimiser's (:class:`ocp.theory.reversal.ReversalRegularity`, see
:func:`ocp.optimize.solve.crossing_order`): ``bounded`` and ``continuous-current`` reverse with the speed
linear in time (thrust exponent ``g = 2``; the current, a state of the motor, is continuous and the
voltage bounded), ``continuous-voltage`` with ``omega ~ s^3`` (``g = 6``; current and voltage both
continuous and zero at the reversal). ``c1-voltage`` is not offered by the stream (it would need the
voltage's slew as a state of the shaper).
"""

from __future__ import annotations

import math
from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ocp.errors import MissionError, validation_location
from ocp.theory.reversal import ReversalRegularity

MIN_DELAY_S = 0.005
MAX_DELAY_S = 1.0
MAX_PREVIEW_SAMPLES = 2000
STREAM_REGULARITIES = (ReversalRegularity.BOUNDED, ReversalRegularity.CONTINUOUS_CURRENT,
                       ReversalRegularity.CONTINUOUS_VOLTAGE)

Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]


class StreamOptions(BaseModel):
    """What one stream needs besides the motor parameters.

    Attributes:
        current: current limit |i| <= current [A]
        voltage: voltage limit |V| <= voltage [V]
        regularity: crossing class (module doc)
        delay: look-ahead D [s]: the output at t tracks the desired thrust at t - D
        dt: sample period [s] of the input stream (uniform)
        bandwidth: closed-loop bandwidth of the speed-space tracker [Hz] (higher tracks closer and
            saturates more often)
        margin: share of each limit kept in reserve against the variation inside one sample (0..0.2)
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    current: Positive
    voltage: Positive
    regularity: ReversalRegularity = ReversalRegularity.CONTINUOUS_VOLTAGE
    delay: Annotated[float, Field(ge=MIN_DELAY_S, le=MAX_DELAY_S, allow_inf_nan=False)] = 0.1
    dt: Annotated[float, Field(gt=0, le=0.05, allow_inf_nan=False)] = 0.001
    bandwidth: Annotated[float, Field(gt=0, le=500, allow_inf_nan=False)] = 20.0
    margin: Annotated[float, Field(ge=0, le=0.2, allow_inf_nan=False)] = 0.02

    @property
    def preview(self) -> int:
        """Look-ahead in samples, ``round(delay / dt)``."""
        return round(self.delay / self.dt)

    @property
    def speed_power(self) -> int:
        """m of ``omega = eta^m``: 1 (g = 2) or 3 (g = 6, continuous voltage)."""
        return 3 if self.regularity is ReversalRegularity.CONTINUOUS_VOLTAGE else 1

    @property
    def chain(self) -> int:
        """Integrator-chain length of the shaper state: 2 (control eta'') or 3 (control eta''')."""
        return 3 if self.regularity is ReversalRegularity.CONTINUOUS_VOLTAGE else 2

    @property
    def exponent(self) -> int:
        """Thrust exponent g at every reversal of the output, ``2 m``."""
        return 2 * self.speed_power


def stream_options(**kwargs: object) -> StreamOptions:
    """:class:`StreamOptions` from keywords; errors are :class:`MissionError` naming the field."""
    try:
        opts = StreamOptions(**kwargs)  # type: ignore[arg-type]
    except ValidationError as exc:
        field, reason = validation_location(exc.errors()[0])
        raise MissionError(field or "stream", reason) from None
    if opts.regularity not in STREAM_REGULARITIES:
        raise MissionError("regularity", f"the stream offers {[r.value for r in STREAM_REGULARITIES]}")
    if opts.preview < 2:
        raise MissionError("delay", f"must span at least 2 samples of dt = {opts.dt} s")
    if opts.preview > MAX_PREVIEW_SAMPLES:
        raise MissionError("delay", f"spans {opts.preview} samples; at most {MAX_PREVIEW_SAMPLES} (raise dt)")
    if not math.isclose(opts.preview * opts.dt, opts.delay, rel_tol=1e-6, abs_tol=1e-12):
        raise MissionError("delay", f"must be a whole number of samples of dt = {opts.dt} s")
    return opts
