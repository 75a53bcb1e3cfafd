"""Mission: what a user asks the optimiser for (validated, unknown keys rejected).

JSON/YAML form::

    {"name": "reversal-1",
     "params": "paper-rig" | {J, B, c_tau, c_f, k_t, k_e, R, L, ...},
     "plant": "dc-motor" | "torque",
     "limits": {"voltage": 12.0, "current": 2.0, "voltage_rate": null, "speed": null, "torque": null},
     "regularity": "bounded" | "continuous-current" | "continuous-voltage" | "c1-voltage",
     "min_crossing_order": null | 2 | 6,
     "objective": "track" | "min-time",
     "retiming": {"min_stretch": 1.0, "max_stretch": 1.5},
     "collocation": {"intervals": 120},
     "time_limit_s": 10.0,
     "profile": {"t": [...], "thrust": [...]}       # sampled desired thrust [s], [N]
       or "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4}, ...]}

Units: voltage [V], current [A], voltage_rate [V/s], speed [rad/s], torque [N m], thrust [N], time [s].

``plant: "torque"`` is the normalised torque channel (paper eq. omega_dyn) for drives that control torque:
its one limit is ``limits.torque`` (default: four times the drag torque at the peak desired thrust,
:meth:`Mission.torque_limit`); the current and voltage it reports are the DC motor's equivalent, not limits.

``min_crossing_order`` is the local exponent ``g`` of the thrust at each reversal, ``|F| ~ |t - t_s|^g``.
The speed must change sign, so ``omega ~ s^(2n+1)`` and ``g = 2(2n+1)``: ``2`` (``omega ~ s``: bounded
current and voltage, the default) or ``6`` (``omega ~ s^3``: current and voltage both zero at the reversal,
which needs the voltage to be a continuous state; the default for ``continuous-voltage`` and
``c1-voltage``). ``g = 4`` would make the speed touch zero
without reversing. Neither is in Table I: ``F ~ sign(s)|s|^g`` is not analytic in time.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
import yaml
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from ocp.errors import MissionError, ParameterError, validation_location
from ocp.model.effects import load_plant
from ocp.model.factory import PlantKind, make_plant
from ocp.model.params import PRESETS, MotorParams, load_params
from ocp.model.plant import DriveBounds, DrivenPlant
from ocp.theory.reversal import ReversalRegularity

MAX_PROFILE_SAMPLES = 100_000
MAX_INTERVALS = 2_000
SEGMENT_RATE = 1000.0  # Hz at which segments are sampled into a profile
OUTPUT_RATE = 1000.0  # Hz of the returned reference arrays
#: longest desired profile [s] (sampled profile span or sum of segment durations): the fallback and the
#: verification work on a 1 kHz grid over it, so its length drives memory and time
MAX_SPAN_S = MAX_PROFILE_SAMPLES / SEGMENT_RATE
#: longest returned reference [s]: the desired span times the largest stretch the retiming allows
MAX_OUTPUT_S = 2.0 * MAX_SPAN_S
#: shortest desired profile [s]: one sample of the returned reference (a shorter one has nothing to answer with,
#: and its collocation intervals divide by its length)
MIN_SPAN_S = 1.0 / OUTPUT_RATE
#: shortest segment [s] (a microsecond: shorter than any drive's PWM period; a denormal 5e-324 s passed before)
MIN_SEGMENT_S = 1e-6
#: largest thrust magnitude [N] anywhere in a mission (a propeller, not a rocket)
MAX_THRUST = 1e3
#: largest magnitude of a profile time stamp [s]
MAX_TIME = 1e6

# strict numbers: JSON numbers only -- "12" and true are refused, ints are taken as floats
Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
PositiveFinite = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
Thrust = Annotated[float, Field(strict=True, ge=-MAX_THRUST, le=MAX_THRUST, allow_inf_nan=False)]
Duration = Annotated[float, Field(strict=True, ge=MIN_SEGMENT_S, le=MAX_SPAN_S, allow_inf_nan=False)]


def _limit(unit: str, top: float, what: str, example: float) -> Any:
    return Field(strict=True, gt=0, le=top, allow_inf_nan=False, description=f"{what} [{unit}], at most {top:g}",
                 examples=[example])


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class Limits(_Strict):
    """Actuator limits (symmetric, magnitudes). ``None`` = unconstrained."""

    voltage: Annotated[float, _limit("V", 1e4, "armature voltage limit |V|", 12.0)] = 12.0
    current: Annotated[float, _limit("A", 1e4, "armature current limit |i|", 2.0)] = 2.0
    voltage_rate: Annotated[float, _limit("V/s", 1e9, "voltage slew limit |dV/dt|", 2000.0)] | None = None
    speed: Annotated[float, _limit("rad/s", 1e6, "rotor speed limit |omega|", 400.0)] | None = None
    torque: Annotated[float, _limit("N m", 1e4, "torque limit of the torque channel", 0.02)] | None = None


class Retiming(_Strict):
    """Each phase may last between ``min_stretch`` and ``max_stretch`` times its desired duration."""

    min_stretch: Annotated[float, Field(strict=True, gt=0, le=100, allow_inf_nan=False, examples=[1.0],
                                        description="shortest phase duration / desired duration [1]")] = 1.0
    max_stretch: Annotated[float, Field(strict=True, gt=0, le=100, allow_inf_nan=False, examples=[1.5],
                                        description="longest phase duration / desired duration [1]")] = 1.5

    @model_validator(mode="after")
    def _ordered(self) -> Retiming:
        if self.max_stretch < self.min_stretch:
            raise ValueError("max_stretch must be >= min_stretch")
        return self


class Collocation(_Strict):
    """Discretisation: total collocation intervals, split over phases by duration."""

    intervals: Annotated[int, Field(strict=True, ge=8, le=MAX_INTERVALS, examples=[120],
                                    description="collocation intervals over the whole horizon [1]")] = 120


class Profile(_Strict):
    """Sampled desired thrust: ``t`` [s] strictly increasing, ``thrust`` [N], equal lengths."""

    t: list[Annotated[float, Field(strict=True, ge=-MAX_TIME, le=MAX_TIME, allow_inf_nan=False)]] = Field(
        min_length=2, max_length=MAX_PROFILE_SAMPLES, examples=[[0.0, 0.5, 1.0]],
        description=f"sample times [s], strictly increasing, spanning at most {MAX_SPAN_S:g} s")
    thrust: list[Thrust] = Field(min_length=2, max_length=MAX_PROFILE_SAMPLES, examples=[[0.3, 0.0, -0.3]],
                                 description=f"desired thrust at each sample [N], |thrust| <= {MAX_THRUST:g}")

    @model_validator(mode="after")
    def _consistent(self) -> Profile:
        if len(self.t) != len(self.thrust):
            raise ValueError(f"t has {len(self.t)} samples but thrust has {len(self.thrust)}")
        if any(b <= a for a, b in zip(self.t, self.t[1:], strict=False)):
            raise ValueError("t must be strictly increasing")
        if not MIN_SPAN_S <= self.t[-1] - self.t[0] <= MAX_SPAN_S:
            raise MissionError("t", f"spans {self.t[-1] - self.t[0]:.4g} s; between {MIN_SPAN_S:g} and "
                                    f"{MAX_SPAN_S:g} s")
        return self


def _duration() -> Any:
    return Field(description=f"segment length [s], {MIN_SEGMENT_S:g} to {MAX_SPAN_S:g}", examples=[0.5])


class Hold(_Strict):
    """Constant thrust ``thrust`` for ``duration``."""

    kind: Literal["hold"]
    duration: Duration = _duration()
    thrust: Thrust = Field(description=f"held thrust [N], |thrust| <= {MAX_THRUST:g}", examples=[0.4])


class Ramp(_Strict):
    """Linear change from the previous level to ``to``."""

    kind: Literal["ramp"]
    duration: Duration = _duration()
    to: Thrust = Field(description="thrust at the end [N]", examples=[0.2])


class Reversal(_Strict):
    """Change from the previous level to ``to`` (opposite sign); ``shape`` of the naive request."""

    kind: Literal["reversal"]
    duration: Duration = _duration()
    to: Thrust = Field(description="thrust at the end [N], opposite in sign to the previous level",
                       examples=[-0.4])
    shape: Literal["cosine", "ramp", "step"] = Field(default="cosine", description="naive shape of the change")


class Sine(_Strict):
    """``offset + amplitude sin(2 pi t/period + phase)`` for ``duration``."""

    kind: Literal["sine"]
    duration: Duration = _duration()
    amplitude: Thrust = Field(description="thrust amplitude [N]", examples=[0.3])
    period: Annotated[float, Field(strict=True, ge=1e-3, le=1e4, allow_inf_nan=False)] = Field(
        description="period [s], 1e-3 to 1e4", examples=[2.0])
    offset: Thrust = Field(default=0.0, description="thrust offset [N]", examples=[0.0])
    phase: Annotated[float, Field(strict=True, ge=-1e3, le=1e3, allow_inf_nan=False)] = Field(
        default=0.0, description="phase [rad], |phase| <= 1000", examples=[0.0])


Segment = Annotated[Hold | Ramp | Reversal | Sine, Field(discriminator="kind")]


class Mission(_Strict):
    """A reference request; see the module doc."""

    name: Annotated[str, Field(min_length=1, max_length=200, description="label echoed in the answer",
                               examples=["reversal-1"])] = "mission"
    params: str | dict[str, Any] = Field(default="paper-rig", examples=["paper-rig"], description=(
        "motor constants: a preset name or a mapping {J [kg m^2], B [N m s/rad], c_tau [N m s^2/rad^2], "
        "c_f [N s^2/rad^2], k_t [N m/A], k_e [V s/rad], R [ohm], L [H], effects?}"))
    plant: PlantKind = Field(default=PlantKind.DC_MOTOR, description="voltage-driven DC motor or "
                             "torque-controlled channel")
    limits: Limits = Field(default=Limits(), description="actuator limits (V, A, V/s, rad/s, N m)")
    regularity: ReversalRegularity = Field(default=ReversalRegularity.BOUNDED,
                                           description="smoothness of the command through a reversal")
    min_crossing_order: Literal[2, 6] | None = Field(default=None, description="local thrust exponent g at "
                                                     "each reversal [1]; null: from the regularity")
    objective: Literal["track", "min-time"] = Field(default="track", description="track the profile or "
                                                    "reach its end as fast as the limits allow")
    retiming: Retiming = Field(default=Retiming(), description="bounds on each phase's stretch [1]")
    collocation: Collocation = Field(default=Collocation(), description="discretisation")
    time_limit_s: Annotated[float, Field(strict=True, gt=0, le=600, allow_inf_nan=False)] = Field(
        default=10.0, description="solver wall-time budget [s], at most 600", examples=[10.0])
    profile: Profile | None = Field(default=None, description="sampled desired thrust (t [s], thrust [N])")
    segments: list[Segment] | None = Field(default=None, min_length=1, max_length=1000,
                                           description="desired thrust as hold/ramp/reversal/sine pieces")
    # parsed once per source object (see motor() and desired())
    #: whether ``params`` may name a parameter file; a validation context ``{"allow_files": ...}`` overrides
    allow_files: ClassVar[bool] = True
    _motor: tuple[object, MotorParams] | None = PrivateAttr(default=None)
    _plant: tuple[object, PlantKind, DrivenPlant] | None = PrivateAttr(default=None)
    _desired: tuple[object, np.ndarray, np.ndarray] | None = PrivateAttr(default=None)
    _bounds: tuple[tuple[object, ...], DriveBounds] | None = PrivateAttr(default=None)

    @field_validator("min_crossing_order")
    @classmethod
    def _order_fits_regularity(cls, v: int | None, info: ValidationInfo) -> int | None:
        if v == 6 and info.data.get("regularity") in ("bounded", "continuous-current"):
            raise ValueError("order 6 needs regularity continuous-voltage or c1-voltage "
                             "(omega ~ s^3 at the reversal needs current and voltage both zero there)")
        return v

    @field_validator("params")
    @classmethod
    def _params_ok(cls, v: str | dict[str, Any], info: ValidationInfo) -> str | dict[str, Any]:
        if isinstance(v, str) and v not in PRESETS and not (info.context or {}).get("allow_files", cls.allow_files):
            raise ParameterError("params", f"must be a preset {list(PRESETS)} or a mapping; files are not read here")
        if isinstance(v, dict) and v.get("effects") is not None:
            load_plant(v)  # the effects block too: ranges checked before any work (ParameterError names the key)
        else:
            load_params(v)  # raises ParameterError naming the key
        return v

    @model_validator(mode="after")
    def _one_profile(self) -> Mission:
        if (self.profile is None) == (self.segments is None):
            raise ValueError("give exactly one of 'profile' and 'segments'")
        if self.segments is not None and not MIN_SPAN_S <= sum(s.duration for s in self.segments) <= MAX_SPAN_S:
            raise MissionError("segments", f"last {self.span():.4g} s; between {MIN_SPAN_S:g} and {MAX_SPAN_S:g} s")
        if self.span() * self.retiming.max_stretch > MAX_OUTPUT_S:
            raise MissionError("retiming.max_stretch", f"a {self.span():.4g} s profile stretched "
                                                       f"{self.retiming.max_stretch:g}x would last longer than "
                                                       f"{MAX_OUTPUT_S:g} s")
        return self

    def span(self) -> float:
        """Length of the desired profile [s] (counted, nothing sampled)."""
        if self.profile is not None:
            return float(self.profile.t[-1] - self.profile.t[0])
        return float(sum(s.duration for s in self.segments or []))

    def motor(self) -> MotorParams:
        """The motor parameters (parsed once: a mapping is validated, a file read, on the first call)."""
        if self._motor is None or self._motor[0] is not self.params:  # a model_copy may change params
            self._motor = (self.params, load_params(self.params))
        return self._motor[1]

    def torque_limit(self) -> float:
        """Torque bound [N m] of the torque channel: ``limits.torque``, else four times the drag torque at
        the peak desired thrust, ``4 c_tau F_peak / c_f``."""
        if self.limits.torque is not None:
            return float(self.limits.torque)
        p = self.motor()
        return 4.0 * p.c_tau * max(float(np.max(np.abs(self.desired()[1]))), 1e-6) / p.c_f

    def drive_plant(self) -> DrivenPlant:
        """The mission's plant (:func:`ocp.model.factory.make_plant`: the DC motor with the effects of ``params``,
        or the torque channel), built once."""
        if self._plant is None or self._plant[0] is not self.params or self._plant[1] is not self.plant:
            self._plant = (self.params, self.plant, make_plant(self.plant, self.params, self.motor()))
        return self._plant[2]

    def bounds(self) -> DriveBounds:
        """The actuator limits resolved (:meth:`torque_limit` filled in), once per limits, profile and params (a
        solve and its verification read them several times; ~20 us each from the samples)."""
        key = (self.limits, self.profile, self.segments, self.params)
        if self._bounds is None or any(a is not b for a, b in zip(self._bounds[0], key, strict=True)):
            lim = self.limits
            self._bounds = (key, DriveBounds(voltage=lim.voltage, current=lim.current, torque=self.torque_limit(),
                                             speed=lim.speed))
        return self._bounds[1]

    def desired(self) -> tuple[np.ndarray, np.ndarray]:
        """Desired thrust samples ``(t [s], thrust [N])``, shapes (N,), t[0] = 0 for segments (sampled once;
        read-only arrays)."""
        source = self.profile if self.profile is not None else self.segments
        if self._desired is None or self._desired[0] is not source:  # a model_copy may change the profile
            if self.profile is not None:
                t, f = np.array(self.profile.t, float), np.array(self.profile.thrust, float)
            else:
                t, f = sample_segments(self.segments or [])
            t.flags.writeable = f.flags.writeable = False
            self._desired = (source, t, f)
        return self._desired[1], self._desired[2]


def output_grid(total: float) -> np.ndarray:
    """Output times [s] at OUTPUT_RATE over ``total``; a horizon over MAX_OUTPUT_S (a min-time solve's
    free horizon) is refused rather than sampled."""
    if not total <= MAX_OUTPUT_S:
        raise MissionError("retiming", f"the reference would last {total:.4g} s; at most {MAX_OUTPUT_S:g} s")
    n = max(2, math.ceil(total * OUTPUT_RATE) + 1)
    return np.linspace(0.0, total, n)


def segment_samples(segments: list[Segment], rate: float = SEGMENT_RATE) -> int:
    """How many samples :func:`sample_segments` makes of ``segments`` (without making them)."""
    return 1 + sum(max(2, math.ceil(seg.duration * rate)) for seg in segments)


def sample_segments(segments: list[Segment], rate: float = SEGMENT_RATE) -> tuple[np.ndarray, np.ndarray]:
    """Concatenate segments into samples at ``rate`` [Hz]; each starts from the previous level."""
    ts: list[np.ndarray] = []
    fs: list[np.ndarray] = []
    level, t0 = 0.0, 0.0
    for seg in segments:
        s = np.linspace(0.0, seg.duration, max(2, math.ceil(seg.duration * rate)) + 1)
        x = s / seg.duration
        if isinstance(seg, Hold):
            f = np.full_like(s, seg.thrust)
        elif isinstance(seg, Ramp) or (isinstance(seg, Reversal) and seg.shape == "ramp"):
            f = level + (seg.to - level) * x
        elif isinstance(seg, Reversal) and seg.shape == "cosine":
            f = level + (seg.to - level) * 0.5 * (1.0 - np.cos(math.pi * x))
        elif isinstance(seg, Reversal):
            f = np.where(x < 0.5, level, seg.to)
        else:
            f = seg.offset + seg.amplitude * np.sin(2 * math.pi * s / seg.period + seg.phase)
        keep = slice(0, None) if not ts else slice(1, None)  # segments share their boundary sample
        ts.append(t0 + s[keep])
        fs.append(f[keep])
        t0 += seg.duration
        level = float(f[-1])
    return np.concatenate(ts), np.concatenate(fs)


def mission_from_mapping(data: Any, allow_files: bool = True) -> Mission:
    """Validate a mapping into a :class:`Mission`; errors name the field path and the reason.

    With ``allow_files=False`` (untrusted input, e.g. over HTTP) ``params`` may only be a preset
    name or an inline mapping, never a path to a file on this machine.
    """
    if not isinstance(data, dict):
        raise MissionError("mission", "must be a mapping (JSON object)")
    try:
        return Mission.model_validate(data, context={"allow_files": allow_files})
    except ValidationError as exc:
        field, reason = validation_location(exc.errors()[0])
        raise MissionError(field or "mission", reason) from None


class YamlLoader(yaml.SafeLoader):
    """Safe YAML with YAML 1.2 floats: ``1e-3`` is a number, not a string (missions take strict numbers)."""


YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?(?:[eE][-+]?[0-9]+)?|\.[0-9_]+(?:[eE][-+]?[0-9]+)?"
               r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"),
    list("-+0123456789."))


def load_mission(path: str | Path) -> Mission:
    """Read a mission from a JSON or YAML file."""
    p = Path(path)
    if not p.is_file():
        raise MissionError("mission", f"no such file: {p}")
    text = p.read_text(encoding="utf-8")
    try:
        data = json.loads(text) if p.suffix.lower() == ".json" else yaml.load(text, Loader=YamlLoader)
    except (json.JSONDecodeError, yaml.YAMLError) as exc:
        raise MissionError("mission", f"{p.name} is not valid JSON/YAML: {exc}") from None
    return mission_from_mapping(data)
