"""``POST /v1/model-check/{check,diagnose,fit}``: upload a rig log, confront the model with it.

``multipart/form-data``: ``log`` (CSV, Parquet, ``.xlsx``, ``.mat``, PX4 ``.ulg`` or ArduPilot ``.bin``,
by file name suffix or content), ``params`` (a preset name or the JSON text of a parameter mapping,
optionally with an ``effects`` block -- never a server path), optional ``columns`` (JSON column map,
see :mod:`ocp.logs`), ``steady_state`` (``true``/``false``; omitted: detected), the read options
``pole_pairs``, ``neutral_us``, ``throttle_range_us``, ``electrical``, ``motor``, ``resample``
(:class:`ocp.logs.ReadOptions`); ``/fit`` also ``effects`` (comma-separated names). The answer is the
core result's ``to_dict()`` with the equations checked and not (``equations``) and what the reader
did (``notes``); ``/check?report=html`` answers the self-contained HTML report. The work runs in a
worker process under the hard ``task_timeout_s``.

Problems (problem+json) name the ``field`` -- a form field, or the log column a :class:`LogError`
names -- and ``form_field``, the form input to show them next to (``log`` for a column).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Depends, File, Form, Query, UploadFile
from fastapi.responses import HTMLResponse

from ocp.errors import ThrustshapeError
from service.api.deps import PoolDep, SettingsDep, TasksDep
from service.api.problems import TooLarge, error_responses
from service.errors import FeatureUnavailable
from service.modelcheck import PARAMS_HELP, READ_FIELDS, Op, parse_columns, parse_effects, parse_params, parse_read
from service.schemas import CheckPublic, DiagnosePublic, FitPublic
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
) -> dict[str, Any]:
    """The read options (:class:`ocp.logs.ReadOptions`) of a model-check upload, checked here."""
    with _form_field():
        return parse_read(pole_pairs=pole_pairs, neutral_us=neutral_us, throttle_range_us=throttle_range_us,
                          electrical=electrical, motor=motor, resample=resample)


ReadForm = Annotated[dict[str, Any], Depends(read_form)]


FORM_FIELDS = ("log", "params", "effects", "columns", *READ_FIELDS)


@contextmanager
def _form_field() -> Iterator[None]:
    """Tag errors with ``form_field``, the form input they belong to: the form field ``field`` starts with
    (``params.effects.coulomb_friction.omega_eps`` -> ``params``), or ``log`` when ``field`` names a column
    of the log (the problem+json then carries both)."""
    try:
        yield
    except ThrustshapeError as exc:
        head = exc.field.split(".", 1)[0]  # "params.effects.stribeck.omega_s" belongs to the params input
        form = head if head in FORM_FIELDS else "log"
        exc.form_field = form  # type: ignore[attr-defined]
        raise


async def _run(op: Op, log: UploadFile, params: str, columns: str | None, steady_state: bool | None, settings: Settings,
               pool: WorkerPool, tasks: TaskSet, **extra: Any) -> dict[str, Any]:
    with _form_field():
        return await _checked(op, log, params, columns, steady_state, settings, pool, tasks, **extra)


async def _checked(op: Op, log: UploadFile, params: str, columns: str | None, steady_state: bool | None,
                   settings: Settings, pool: WorkerPool, tasks: TaskSet, **extra: Any) -> dict[str, Any]:
    if tasks.model_check is None:  # the routes are only registered when the backend exists
        raise FeatureUnavailable("model checks", "ocp.identify")
    source = parse_params(params)
    column_map = parse_columns(columns)
    if log.size is not None and log.size > settings.max_upload_bytes:
        raise TooLarge("log", f"{log.size} bytes; this server accepts logs of at most {settings.max_upload_bytes}")
    data = await log.read(settings.max_upload_bytes + 1)
    if len(data) > settings.max_upload_bytes:
        raise TooLarge("log", f"larger than {settings.max_upload_bytes} bytes, the most this server accepts")
    payload = {"op": op, "log": data, "filename": log.filename, "params": source, "columns": column_map,
               "steady_state": steady_state, "max_samples": settings.max_log_samples, **extra}
    return await pool.run(tasks.model_check, payload, settings.task_timeout_s)


@router.post("/check", response_model=CheckPublic,
             responses={**_ERRORS, 200: {"content": {"text/html": {}},
                                         "description": "the result as JSON, or the HTML report (report=html)"}},
             summary="Where does the model fail on this log? Free-run and one-step errors, broken down")
async def check(log: LogFile, params: ParamsField, settings: SettingsDep, pool: PoolDep, tasks: TasksDep,
                read: ReadForm, columns: ColumnsField = None, steady_state: SteadyField = None,
                report: Annotated[Literal["json", "html"], Query(description="html: the self-contained report")]
                = "json") -> Any:
    out = await _run("check", log, params, columns, steady_state, settings, pool, tasks, report=report == "html",
                     read=read)
    if report == "html":
        return HTMLResponse(out["html"])
    return out


@router.post("/diagnose", response_model=DiagnosePublic, responses=_ERRORS,
             summary="Which catalogue effect is missing? Candidates ranked by held-out error reduction")
async def diagnose(log: LogFile, params: ParamsField, settings: SettingsDep, pool: PoolDep, tasks: TasksDep,
                   read: ReadForm, columns: ColumnsField = None, steady_state: SteadyField = None,
                   max_effects: Annotated[int, Form(ge=1, le=10, description="at most this many effects")] = 3,
                   corrections: Annotated[bool, Form(description="also try corrections of the nominal constants")]
                   = True) -> Any:
    return await _run("diagnose", log, params, columns, steady_state, settings, pool, tasks,
                      options={"max_effects": max_effects, "include_params": corrections}, read=read)


@router.post("/fit", response_model=FitPublic, responses=_ERRORS,
             summary="Add named effects, refit, answer before/after errors and the calibrated parameters")
async def fit(log: LogFile, params: ParamsField,
              effects: Annotated[str, Form(min_length=1, max_length=2_000,
                                           description="comma-separated effect names (see GET /v1/info) or "
                                                       "param:<key> corrections")],
              settings: SettingsDep, pool: PoolDep, tasks: TasksDep, read: ReadForm, columns: ColumnsField = None,
              steady_state: SteadyField = None,
              refine: Annotated[bool, Form(description="free-run refinement after the equation-error fit")] = True,
              ) -> Any:
    with _form_field():
        names = parse_effects(effects)
    return await _run("fit", log, params, columns, steady_state, settings, pool, tasks, effects=names,
                      options={"refine": refine}, read=read)
