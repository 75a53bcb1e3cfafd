"""Request and response bodies of the HTTP API (pydantic v2).

Missions are :class:`ocp.optimize.mission.Mission` itself (subclassed only to refuse parameter *file paths*:
over HTTP ``params`` is a preset name or a mapping, never a path on the server). Bodies reject
unknown fields. Responses that mirror a core result's ``to_dict()`` list the documented fields and
allow extra ones the core may add.
"""

from __future__ import annotations

from typing import Annotated, Any, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, field_validator, model_validator

from ocp.errors import ParameterError
from ocp.model.params import PRESETS, load_params
from ocp.optimize.mission import MAX_SPAN_S, MAX_THRUST, Limits, Mission
from ocp.theory.reversal import ReversalRegularity
from service.core_models import OptimizePublic  # noqa: F401  (generated from the core's result types)

# strict numbers: "12" and true are not numbers
Finite = Annotated[float, Field(strict=True, allow_inf_nan=False)]
PositiveFinite = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
Amplitude = Annotated[float, Field(strict=True, ge=-MAX_THRUST, le=MAX_THRUST, allow_inf_nan=False)]
Period = Annotated[float, Field(strict=True, ge=1e-3, le=1e4, allow_inf_nan=False)]
#: a sample of a reference channel: a number, or "inf"/"-inf" where the ideal command is unbounded
Sample = float | Literal["inf", "-inf"]


#: request-body examples shown in the OpenAPI document (and tried by tests/test_openapi_conventions.py)
MISSION_EXAMPLE: dict[str, Any] = {
    "name": "reversal-2s", "params": "paper-rig", "limits": {"voltage": 12.0, "current": 1.0},
    "regularity": "bounded", "objective": "track", "retiming": {"min_stretch": 1.0, "max_stretch": 1.5},
    "segments": [{"kind": "hold", "duration": 0.8, "thrust": 0.4},
                 {"kind": "reversal", "duration": 0.4, "to": -0.4, "shape": "cosine"},
                 {"kind": "hold", "duration": 0.8, "thrust": -0.4}]}
SIN_EXAMPLE: dict[str, Any] = {"params": "paper-rig", "amplitude": 0.5, "period": 2.0, "q": 2, "rate": 200.0}
DESIGN_EXAMPLE: dict[str, Any] = {"params": "paper-rig", "amplitude": 0.4, "limits": {"voltage": 12.0, "current": 1.0},
                                  "regularity": "continuous-voltage", "rate": 200.0}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow")


def preset_or_mapping(v: Any) -> Any:
    """Before-validator: a string must name a preset (no file paths over HTTP)."""
    if isinstance(v, str) and v not in PRESETS:
        raise ParameterError("params", f"unknown preset {v!r}; presets are {list(PRESETS)} (or give a mapping)")
    return v


class MissionRequest(Mission):
    """A :class:`ocp.optimize.mission.Mission`; ``params`` is a preset name or a parameter mapping, never a file
    path (the core's rule, switched on for the class since FastAPI cannot pass a validation context)."""

    model_config = ConfigDict(title="Mission", json_schema_extra={"examples": [MISSION_EXAMPLE]})
    allow_files: ClassVar[bool] = False


class _ParamsMixin(_Strict):
    params: str | dict[str, Any] = Field(default="paper-rig", description=f"preset ({', '.join(PRESETS)}) "
                                         "or mapping {J, B, c_tau, c_f, k_t, k_e, R, L[, units]}")
    duration: Annotated[float, Field(strict=True, gt=0, le=MAX_SPAN_S, allow_inf_nan=False)] | None = Field(
        default=None, description=f"length [s], at most {MAX_SPAN_S:g}; default one period", examples=[2.0])
    rate: Annotated[float, Field(strict=True, gt=0, le=1e6, allow_inf_nan=False)] = Field(
        default=1000.0, description="sampling rate [Hz]", examples=[1000.0])

    @field_validator("params", mode="before")
    @classmethod
    def _no_paths(cls, v: Any) -> Any:
        return preset_or_mapping(v)

    @field_validator("params")
    @classmethod
    def _params_ok(cls, v: str | dict[str, Any]) -> str | dict[str, Any]:
        load_params(v)  # ParameterError names the key
        return v


class SinRequest(_ParamsMixin):
    """Exact feedforward of ``F = A sin^(2q+1)(2 pi t/T + phi)``."""

    model_config = ConfigDict(json_schema_extra={"examples": [SIN_EXAMPLE]})

    kind: Literal["sin"] = "sin"
    amplitude: Amplitude = Field(description=f"thrust amplitude A [N], non-zero, |A| <= {MAX_THRUST:g}",
                                 examples=[0.5])
    period: Period = Field(description="period T [s], 1e-3 to 1e4", examples=[2.0])
    q: Annotated[int, Field(strict=True, ge=0, le=20, description="thrust ~ sin^(2q+1)", examples=[2])]
    phase: Annotated[float, Field(strict=True, ge=-1e3, le=1e3, allow_inf_nan=False)] = Field(
        default=0.0, description="phase phi [rad], |phi| <= 1000", examples=[0.0])

    @field_validator("amplitude")
    @classmethod
    def _nonzero(cls, v: float) -> float:
        if v == 0:
            raise ValueError("must be non-zero")
        return v


class DesignRequest(_ParamsMixin):
    """Analytic fallback design: smallest admissible q for ``regularity``, then the shortest period
    (``amplitude`` given) or largest amplitude (``period`` given) within ``limits``."""

    model_config = ConfigDict(json_schema_extra={"examples": [DESIGN_EXAMPLE]})

    kind: Literal["design"] = "design"
    limits: Limits = Limits()
    regularity: ReversalRegularity = ReversalRegularity.CONTINUOUS_VOLTAGE
    amplitude: Amplitude | None = Field(default=None, description="thrust amplitude [N] (or give period)",
                                        examples=[0.4])
    period: Period | None = Field(default=None, description="period [s] (or give amplitude)")

    @model_validator(mode="after")
    def _one_of(self) -> DesignRequest:
        if (self.amplitude is None) == (self.period is None):
            raise ValueError("give exactly one of 'amplitude' and 'period'")
        if self.amplitude == 0:
            raise ValueError("amplitude must be non-zero")
        return self


def _analytic_kind(v: Any) -> str:
    if isinstance(v, dict):
        kind = v.get("kind")
        if kind in ("sin", "design"):
            return str(kind)
        return "design" if "limits" in v or "regularity" in v or "q" not in v else "sin"
    return str(getattr(v, "kind", "sin"))


AnalyticRequest = Annotated[
    Annotated[SinRequest, Tag("sin")] | Annotated[DesignRequest, Tag("design")],
    Discriminator(_analytic_kind),
]


class CrossingPublic(_Open):
    t: float = Field(description="crossing time [s]")
    p: int | None = Field(default=None, description="thrust order at the crossing")


class DesignPublic(_Strict):
    q: int
    amplitude: float = Field(description="[N]")
    period: float = Field(description="[s]")
    peak_current: float = Field(description="[A]")
    peak_voltage: float = Field(description="[V]")


class ReferencePublic(_Open):
    """:meth:`ocp.reference.trajectory.Reference.to_dict`; arrays of shape (N,), SI units, "inf" where unbounded."""

    t: list[Sample]
    thrust: list[Sample]
    omega: list[Sample]
    omega_dot: list[Sample]
    omega_ddot: list[Sample]
    theta: list[Sample]
    current: list[Sample]
    voltage: list[Sample]
    unbounded: dict[str, bool]
    crossings: list[CrossingPublic]
    design: DesignPublic | None = None


class CheckPublic(_Open):
    """:meth:`ocp.identify.CheckResult.to_dict`: where the model fails (free-run and one-step errors, breakdowns)."""

    kind: Literal["time-series", "steady-state"]
    free_run: dict[str, Any] = Field(description="label, rms, max, units per channel (omega, current, thrust); "
                                                 "current_sensor_lag [samples]: the current sensor's first-order lag "
                                                 "the simulated current was read through")
    one_step: dict[str, Any] = Field(description="label, rms, mean, units per equation")
    noise: dict[str, float | None]
    breakdown: dict[str, Any] = Field(description="group -> bin -> statistics")
    correlation: dict[str, Any] = Field(description="residual auto/cross-correlations and the 95 % band")
    alignment: dict[str, Any] | None = Field(default=None, description="the command-to-sensor lag logging "
                                             "conventions explain, removed before comparing (time series)")


class DiagnosePublic(_Open):
    """:meth:`ocp.identify.DiagnoseResult.to_dict`: which effects are missing, most important first."""

    verdict: list[str] = Field(description="missing effects, most important first; empty: nothing missing")
    ranking: list[dict[str, Any]] = Field(description="first round: every candidate by held-out error reduction")
    explanations: list[str]
    message: str
    noise: dict[str, float | None]
    rounds: list[dict[str, Any]]
    blind_spots: list[dict[str, Any]] = Field(
        default_factory=list, description="[{gap, text, hidden, design}] what the log cannot show and the effects and "
        "constants it hides, those in the verdict left out: a time series with no reversal, no time at low speed, "
        "one speed, one voltage magnitude or no rows slow enough for a 64-period ripple (design-experiment probes "
        "them); a log checked point by point that turns one way only (no drag or thrust asymmetry)")
    evidence: dict[str, dict[str, Any]] = Field(
        default_factory=dict, description="per verdict name, how it won beside the other names: {test, strong, says, "
        "z, heldout}; test likelihood_ratio, beyond_sampling or alignment (strong), inductance_timing, "
        "held_out_blocks, estimate, ripple_rows or with_others (weak); z: the torque equation's likelihood-ratio z "
        "(null where the name does not enter it); heldout: per equation it enters, the held-out RMS in noise units "
        "without it and with it (ocp/identify/strength.py; empty on a log checked point by point)")


class FitPublic(_Open):
    """:meth:`ocp.identify.FitResult.to_dict` plus ``calibrated_params``, the calibrated parameter mapping
    (readable by :func:`ocp.model.effects.load_plant`, and as ``params`` of a mission or a model check)."""

    effects: list[str]
    stage: Literal["equation-error", "free-run"]
    adopted: bool = Field(default=True, description="False: the fit predicted the log's free run worse than the "
                          "starting plant; calibrated_params is then the starting plant (why in note)")
    note: str | None = None
    parameters: dict[str, dict[str, float | None]] = Field(description="name -> {value, stderr}")
    rms_before: dict[str, float | None]
    rms_after: dict[str, float | None]
    current_sensor_lag: dict[str, float] | None = Field(
        default=None, description="[samples] before, after: the current sensor's first-order lag the free run's "
        "current was read through")
    alignment: dict[str, Any] | None = Field(default=None, description="the command-to-sensor lag logging "
                                             "conventions explain, removed before fitting (time series)")
    calibrated_params: dict[str, Any]


class ExperimentDesignPublic(_Open):
    """:meth:`ocp.identify.design.DesignResult.to_dict` plus ``diagnosis`` (the diagnosis it settles): why an
    experiment is needed, the rival explanations, every candidate excitation's separation, the chosen mission."""

    needed: bool = Field(description="false: not ambiguous and the log covers reversals, low speed, a speed range, "
                                     "rows slow enough for a 64-period angle ripple and a range of voltages")
    reasons: list[str]
    coverage: dict[str, Any] = Field(description="reversal, forward, low_speed, speed_range, ripple_reach, "
                                     "voltage_range (bool) and the fractions behind; ripple_periods: the largest "
                                     "angle ripple count resolved on half the moving rows")
    rivals: list[dict[str, Any]] = Field(description="[{name, items}] the explanations to separate")
    candidates: list[dict[str, Any]] = Field(description="every excitation: runnable, separation per rival pair")
    separation: float | None = Field(description="the chosen experiment's smallest pairwise separation z "
                                                 "[noise standard deviations]")
    misclassification: float | None = Field(description="Phi(-z/2): probability a likelihood-ratio test confuses "
                                                        "the closest pair")
    mission: dict[str, Any] | None = Field(description="the proposed mission (POST it to /v1/references/optimize)")
    logging: dict[str, Any] | None = Field(
        default=None, description="where the log is too slow to check a constant (L/R under two samples): "
        "{constant, log_rate_hz, resolves_from_hz, rate_hz (advised), reason}")
    message: str
    diagnosis: dict[str, Any]


class BatchCreate(_Strict):
    model_config = ConfigDict(json_schema_extra={"examples": [{"missions": [MISSION_EXAMPLE]}]})

    missions: list[MissionRequest] = Field(min_length=1, description="missions to optimise, in order")


class BatchAccepted(_Strict):
    id: str
    status: Literal["queued", "running", "done", "failed"]


class BatchCountsPublic(_Strict):
    total: int
    queued: int
    running: int
    done: int
    failed: int


class BatchPublic(_Strict):
    id: str
    status: Literal["queued", "running", "done", "failed"]
    created_at: float = Field(description="Unix time [s]")
    counts: BatchCountsPublic
    progress: float = Field(ge=0, le=1, description="finished items / total")


class ItemError(_Open):
    type: str = Field(description="error class, e.g. MissionError, TaskTimeout")
    field: str | None = None
    reason: str


class BatchItemPublic(_Strict):
    index: int
    name: str
    status: Literal["queued", "running", "done", "failed"]
    attempts: int
    result: dict[str, Any] | None = None
    error: ItemError | None = None


class BatchResults(_Strict):
    id: str
    status: Literal["queued", "running", "done", "failed"]
    results: list[BatchItemPublic]


class LimitsPublic(_Strict):
    max_body_bytes: int
    max_profile_samples: int
    max_intervals: int
    max_batch_missions: int
    max_reference_samples: int
    max_upload_bytes: int
    max_log_samples: int
    optimize_deadline_s: float
    task_timeout_s: float


class InfoPublic(_Strict):
    version: str
    presets: list[str]
    effects: list[str]
    regularities: list[str]
    limits: LimitsPublic
    features: dict[str, bool] = Field(description="which optional routes this server offers")
    workers: int
    batch_backend: Literal["local", "dask"]


class StorePublic(_Strict):
    ok: bool = Field(description="the job store file is in place and answers")
    detail: str | None = Field(default=None, description="what is wrong with it")


class RunnerPublic(_Strict):
    state: Literal["running", "retrying", "stopped"] = Field(description="retrying: store writes fail, outcomes "
                                                             "are kept in memory and retried with backoff")
    unsaved: int = Field(description="batch outcomes computed but not yet stored")
    inflight: int = Field(description="batch items being computed")
    last_error: str | None = Field(default=None, description="the last store error, null once a write succeeds")


class WorkersPublic(_Strict):
    size: int = Field(description="solver worker processes")
    alive: int = Field(description="of which alive now (a killed one is replaced on its next task)")
    ready: int = Field(description="of which started (imports done); the others are still starting")
    pending: int = Field(description="requests running or waiting for a worker")


class Health(_Strict):
    status: Literal["ok", "degraded"] = "ok"
    store: StorePublic | None = None
    runner: RunnerPublic | None = None
    workers: WorkersPublic | None = None
    fallback_workers: WorkersPublic | None = Field(default=None, description="processes of the analytic fallback")


class Problem(_Open):
    """RFC 9457 problem details; ``field`` and ``reason`` name what was wrong."""

    type: str = Field(default="about:blank", description="problem type URI (about:blank: see title/status)")
    title: str = Field(description="short summary of the problem type, e.g. 'Invalid input'")
    status: int = Field(description="the HTTP status code")
    detail: str = Field(description="what went wrong, for a person")
    field: str | None = Field(default=None, description="the input at fault: a dotted body path "
                              "(limits.current, segments.1.duration), a form field, a log column or a header")
    reason: str | None = Field(default=None, description="why that input was refused")


ModelCheckOp = Literal["check", "diagnose", "fit", "design"]
JobStatus = Literal["queued", "running", "done", "failed"]


class ModelCheckJobPublic(_Strict):
    """A model-check job: ``status``, ``progress`` (0..1, while running), the error once failed."""

    id: str
    op: ModelCheckOp
    status: JobStatus
    progress: float = Field(ge=0, le=1)
    attempts: int
    created_at: float = Field(description="Unix time [s]")
    finished_at: float | None = None
    error: ItemError | None = None
