"""``POST /v1/model-check/{check,diagnose,fit}``: upload a rig log, confront the model with it.

``multipart/form-data``: ``log`` (CSV, Parquet, ``.xlsx``, ``.mat``, PX4 ``.ulg`` or ArduPilot ``.bin``,
by file name suffix or content), ``params`` (a preset name or the JSON text of a parameter mapping,
optionally with an ``effects`` block -- never a server path), optional ``columns`` (JSON column map,
see :mod:`ocp.logs`), ``steady_state`` (``true``/``false``; omitted: detected), the read options
``pole_pairs``, ``neutral_us``, ``throttle_range_us``, ``electrical``, ``motor``, ``resample``, ``negate``
(:class:`ocp.logs.ReadOptions`); ``/fit`` also ``effects`` (comma-separated names). The answer is the
core result's ``to_dict()`` with the equations checked and not (``equations``) and what the reader
did (``notes``); ``/check?report=html`` answers the self-contained HTML report. The work runs in a
worker process under the hard ``task_timeout_s``.

Problems (problem+json) name the ``field`` -- a form field, or the log column a :class:`LogError`
names -- and ``form_field``, the form input to show them next to (``log`` for a column).
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated, Any, Literal, cast

from fastapi import APIRouter, Depends, File, Form, Path, Query, Request, Response, UploadFile
from fastapi.responses import HTMLResponse
from starlette.exceptions import HTTPException

from ocp.errors import ParameterError, ThrustshapeError
from service.api.deps import PoolDep, SettingsDep, TasksDep
from service.api.problems import TooLarge, error_responses, problem
from service.checkjobs import CheckJob, CheckJobRunner
from service.errors import FeatureUnavailable
from service.modelcheck import (
    PARAMS_HELP,
    READ_FIELDS,
    Op,
    parse_columns,
    parse_effects,
    parse_params,
    parse_read,
    parse_rivals,
)
from service.schemas import (
    CheckPublic,
    DiagnosePublic,
    ExperimentDesignPublic,
    FitPublic,
    ItemError,
    ModelCheckJobPublic,
    ModelCheckOp,
)
from service.settings import Settings
from service.tasks import TaskSet
from service.workers import WorkerPool

PREFIX = "/v1/model-check"
router = APIRouter(prefix=PREFIX, tags=["model check"])
_ERRORS = error_responses(401, 413, 422, 501, 503, 504)

LogFile = Annotated[UploadFile, File(description="measurement log: CSV (header row) or Parquet; columns t, voltage, "
                                                 "current, omega and/or theta, thrust (SI) or as `columns` maps them")]
ParamsField = Annotated[str, Form(min_length=1, max_length=200_000, description=PARAMS_HELP)]
ColumnsField = Annotated[str | None, Form(max_length=20_000, description='column map as JSON, e.g. {"omega": '
                                                                         '{"column": "speed", "unit": "rpm"}}')]
SteadyField = Annotated[bool | None, Form(description="the log is a steady-state sweep (one row per operating "
                                                     "point); omitted: detected where the file makes it plain")]


MaxEffectsField = Annotated[int, Form(ge=1, le=10, description="at most this many effects in the verdict")]
CorrectionsField = Annotated[bool, Form(description="also try corrections of the nominal constants")]
ToleranceField = Annotated[float, Form(gt=0, lt=1, description="a constant is named wrong only beyond this "
                                                               "relative error (default 0.10)")]
SkewField = Annotated[float, Form(ge=0, le=20, description="command-to-sensor lag [samples] that logging "
                                                           "conventions explain; beyond it: input_delay")]


def read_form(
    pole_pairs: Annotated[int | None, Form(ge=1, le=100, description="motor pole pairs, to turn an electrical "
                                                                     "speed (eRPM) column into rad/s")] = None,
    neutral_us: Annotated[float, Form(ge=500, le=2500, description="ESC neutral pulse [us]: unsigned speed, "
                                                                   "thrust and torque take sign(command - neutral)")]
    = 1500.0,
    throttle_range_us: Annotated[str | None, Form(max_length=40, description='"min,max" ESC pulse range [us], '
                                                                              'default "1100,1900"')] = None,
    electrical: Annotated[Literal["auto", "armature", "supply"], Form(
        description="whose voltage/current the log holds; auto: the supply's when there is an ESC command")] = "auto",
    motor: Annotated[int, Form(ge=0, le=15, description="which motor/ESC of a flight log")] = 0,
    resample: Annotated[Literal["auto", "refuse"], Form(description="irregular timestamps: resample (stated in "
                                                                    "the answer) or refuse")] = "auto",
    negate: Annotated[str | None, Form(max_length=60, description="channels logged with the opposite sign to the "
                                       "model's, comma-separated (voltage, current, omega, thrust, torque)")] = None,
) -> dict[str, Any]:
    """The read options (:class:`ocp.logs.ReadOptions`) of a model-check upload, checked here."""
    with _form_field():
        return parse_read(pole_pairs=pole_pairs, neutral_us=neutral_us, throttle_range_us=throttle_range_us,
                          electrical=electrical, motor=motor, resample=resample, negate=negate)


ReadForm = Annotated[dict[str, Any], Depends(read_form)]


FORM_FIELDS = ("log", "params", "effects", "columns", "rivals", "voltage", "current", "duration_s", *READ_FIELDS)


@contextmanager
def _form_field() -> Iterator[None]:
    """Tag errors with ``form_field``, the form input they belong to: the form field ``field`` starts with
    (``params.effects.coulomb_friction.omega_eps`` -> ``params``), or ``log`` when ``field`` names a column
    of the log (the problem+json then carries both)."""
    try:
        yield
    except ThrustshapeError as exc:
        exc.form_field = form_field_of(exc.field)  # type: ignore[attr-defined]
        raise


def form_field_of(field: str | None) -> str | None:
    """The form input a problem's ``field`` belongs to (a log column: ``log``)."""
    if field is None:
        return None
    head = field.split(".", 1)[0]  # "params.effects.stribeck.omega_s" belongs to the params input
    return head if head in FORM_FIELDS else "log"


async def _run(op: Op, log: UploadFile, params: str, columns: str | None, steady_state: bool | None, settings: Settings,
               pool: WorkerPool, tasks: TaskSet, **extra: Any) -> dict[str, Any]:
    with _form_field():
        return await _checked(op, log, params, columns, steady_state, settings, pool, tasks, **extra)


async def _checked(op: Op, log: UploadFile, params: str, columns: str | None, steady_state: bool | None,
                   settings: Settings, pool: WorkerPool, tasks: TaskSet, **extra: Any) -> dict[str, Any]:
    if tasks.model_check is None:  # the routes are only registered when the backend exists
        raise FeatureUnavailable("model checks", "ocp.identify")
    payload = await _payload(op, log, params, columns, steady_state, settings, **extra)
    return await pool.run(tasks.model_check, payload, settings.task_timeout_s)


async def _payload(op: Op, log: UploadFile, params: str, columns: str | None, steady_state: bool | None,
                   settings: Settings, **extra: Any) -> dict[str, Any]:
    """The worker task's payload, every field checked and the upload read within its limit."""
    source = parse_params(params)
    column_map = parse_columns(columns)
    if log.size is not None and log.size > settings.max_upload_bytes:
        raise TooLarge("log", f"{log.size} bytes; this server accepts logs of at most {settings.max_upload_bytes}")
    data = await log.read(settings.max_upload_bytes + 1)
    if len(data) > settings.max_upload_bytes:
        raise TooLarge("log", f"larger than {settings.max_upload_bytes} bytes, the most this server accepts")
    return {"op": op, "log": data, "filename": log.filename, "params": source, "columns": column_map,
            "steady_state": steady_state, "max_samples": settings.max_log_samples, **extra}


@router.post("/check", response_model=CheckPublic,
             responses={**_ERRORS, 200: {"content": {"text/html": {}},
                                         "description": "the result as JSON, or the HTML report (report=html)"}},
             summary="Where does the model fail on this log? Free-run and one-step errors, broken down")
async def check(log: LogFile, params: ParamsField, settings: SettingsDep, pool: PoolDep, tasks: TasksDep,
                read: ReadForm, columns: ColumnsField = None, steady_state: SteadyField = None,
                report: Annotated[Literal["json", "html"], Query(description="html: the self-contained report")]
                = "json", max_logging_skew: SkewField = 2.0) -> Any:
    out = await _run("check", log, params, columns, steady_state, settings, pool, tasks, report=report == "html",
                     options={"max_logging_skew": max_logging_skew}, read=read)
    if report == "html":
        return HTMLResponse(out["html"])
    return out


@router.post("/diagnose", response_model=DiagnosePublic, responses=_ERRORS,
             summary="Which catalogue effect is missing? Candidates ranked by held-out error reduction")
async def diagnose(log: LogFile, params: ParamsField, settings: SettingsDep, pool: PoolDep, tasks: TasksDep,
                   read: ReadForm, columns: ColumnsField = None, steady_state: SteadyField = None,
                   max_effects: Annotated[int, Form(ge=1, le=10, description="at most this many effects")] = 3,
                   corrections: Annotated[bool, Form(description="also try corrections of the nominal constants")]
                   = True, tolerance: ToleranceField = 0.10, max_logging_skew: SkewField = 2.0) -> Any:
    return await _run("diagnose", log, params, columns, steady_state, settings, pool, tasks,
                      options=_diagnose_options(max_effects, corrections, tolerance, max_logging_skew), read=read)


def _diagnose_options(max_effects: int, corrections: bool, tolerance: float, skew: float) -> dict[str, Any]:
    """:class:`ocp.identify.DiagnoseOptions` fields (the form's bounds are the options' own)."""
    return {"max_effects": max_effects, "include_params": corrections, "tolerance": tolerance,
            "max_logging_skew": skew}


@router.post("/fit", response_model=FitPublic, responses=_ERRORS,
             summary="Add named effects, refit, answer before/after errors and the calibrated parameters")
async def fit(log: LogFile, params: ParamsField,
              effects: Annotated[str, Form(min_length=1, max_length=2_000,
                                           description="comma-separated effect names (see GET /v1/info) or "
                                                       "param:<key> corrections")],
              settings: SettingsDep, pool: PoolDep, tasks: TasksDep, read: ReadForm, columns: ColumnsField = None,
              steady_state: SteadyField = None,
              refine: Annotated[bool, Form(description="free-run refinement after the equation-error fit")] = True,
              max_logging_skew: SkewField = 2.0) -> Any:
    with _form_field():
        names = parse_effects(effects)
    return await _run("fit", log, params, columns, steady_state, settings, pool, tasks, effects=names,
                      options={"refine": refine, "max_logging_skew": max_logging_skew}, read=read)


# --- model checks as jobs: 202, poll the status and its progress, fetch the result (service/checkjobs.py) ---

JobId = Annotated[str, Path(min_length=1, max_length=64, description="job id from POST /v1/model-check/jobs")]


def _job_runner(request: Request) -> CheckJobRunner:
    runner = getattr(request.app.state, "check_jobs", None)
    if runner is None:
        raise FeatureUnavailable("model-check jobs", "ocp.identify")
    return cast(CheckJobRunner, runner)


JobsDep = Annotated[CheckJobRunner, Depends(_job_runner)]


def _job_public(job: CheckJob) -> ModelCheckJobPublic:
    err = job.error if job.state == "failed" else None
    return ModelCheckJobPublic(id=job.id, op=cast(Any, job.op), status=job.state, progress=job.progress,
                               attempts=job.attempts, created_at=job.created_at, finished_at=job.finished_at,
                               error=ItemError(**{k: v for k, v in err.items() if v is not None}) if err else None)


async def _job(jobs: CheckJobRunner, job_id: str, full: bool = False) -> CheckJob:
    job = await asyncio.to_thread(jobs.jobs.get, job_id, full)
    if job is None:
        raise HTTPException(404, f"no model-check job {job_id!r}")
    return job


@router.post("/jobs", status_code=202, response_model=ModelCheckJobPublic, responses=_ERRORS,
             summary="Run a model check (check, diagnose, fit or design) as a job: stored, run in a worker, "
                     "with progress; no request timeout")
async def submit_model_check(
    response: Response, log: LogFile, params: ParamsField, settings: SettingsDep, tasks: TasksDep, jobs: JobsDep,
    read: ReadForm,
    op: Annotated[ModelCheckOp, Form(description="check, diagnose, fit (needs effects) or design (the experiment "
                                                 "that settles an ambiguous diagnosis)")] = "diagnose",
    columns: ColumnsField = None, steady_state: SteadyField = None, max_effects: MaxEffectsField = 3,
    corrections: CorrectionsField = True, tolerance: ToleranceField = 0.10, max_logging_skew: SkewField = 2.0,
    effects: Annotated[str | None, Form(max_length=2_000, description="fit: comma-separated effect names")] = None,
    refine: Annotated[bool, Form(description="fit: free-run refinement")] = True,
    voltage: Annotated[float | None, Form(gt=0, le=1e4, description="design: voltage limit [V] (default: the "
                                                                    "log's peak)")] = None,
    current: Annotated[float | None, Form(gt=0, le=1e4, description="design: current limit [A] (default: the "
                                                                    "log's peak)")] = None,
    duration_s: Annotated[float | None, Form(ge=0.2, le=60, description="design: experiment length [s]")] = None,
    rivals: Annotated[str | None, Form(max_length=2_000, description="design: rival explanations, sets separated "
                                                                     "by ';', items by ',' (default: from the "
                                                                     "diagnosis)")] = None,
) -> ModelCheckJobPublic:
    with _form_field():
        extra: dict[str, Any] = {"read": read}
        if op == "fit":
            if effects is None:
                raise ParameterError("effects", "a fit job needs effects (comma-separated names)")
            extra.update(effects=parse_effects(effects), options={"refine": refine,
                                                                   "max_logging_skew": max_logging_skew})
        elif op in ("diagnose", "design"):
            extra["options"] = _diagnose_options(max_effects, corrections, tolerance, max_logging_skew)
        else:
            extra["options"] = {"max_logging_skew": max_logging_skew}
        if op == "design":
            extra["design"] = {"voltage": voltage, "current": current, "duration_s": duration_s,
                               "rivals": parse_rivals(rivals)}
        payload = await _payload(op, log, params, columns, steady_state, settings, **extra)
    data = payload.pop("log")
    job_id = await jobs.submit(op, payload, data)
    response.headers["Location"] = f"{PREFIX}/jobs/{job_id}"
    return _job_public(await _job(jobs, job_id))


@router.get("/jobs/{job_id}", response_model=ModelCheckJobPublic, responses=error_responses(401, 404),
            summary="A model-check job's status and progress")
async def get_model_check(job_id: JobId, jobs: JobsDep) -> ModelCheckJobPublic:
    return _job_public(await _job(jobs, job_id))


@router.get("/jobs/{job_id}/result", responses={**error_responses(401, 404, 409, 422, 500, 504),
                                                200: {"model": CheckPublic | DiagnosePublic | FitPublic
                                                      | ExperimentDesignPublic,
                                                      "description": "the op's result: CheckPublic, "
                                                      "DiagnosePublic, FitPublic or ExperimentDesignPublic"}},
            summary="A finished model-check job's result (409 while it runs; its problem when it failed)")
async def get_model_check_result(job_id: JobId, jobs: JobsDep) -> Any:
    job = await _job(jobs, job_id, full=True)
    if job.state == "done":
        return job.result
    if job.state != "failed":
        return problem(409, "Not finished", f"job {job_id} is {job.state} ({100 * job.progress:.0f} %)")
    err = job.error or {}
    status = {"TaskTimeout": 504, "TaskFailed": 500}.get(str(err.get("type")), 422)
    form = form_field_of(err.get("field")) if err.get("type") not in ("TaskTimeout", "TaskFailed") else None
    extra: dict[str, Any] = {"form_field": form} if form else {}
    return problem(status, "Model check failed", f"{err.get('field')}: {err.get('reason')}", err.get("field"),
                   err.get("reason"), error_type=err.get("type"), **extra)
