"""Model-check inputs as they arrive over HTTP, checked in the server before a worker is used, and the
worker task that reads the uploaded log and runs :mod:`ocp.identify`.

Every problem raises a :class:`~ocp.errors.ThrustshapeError` whose ``field`` is the form field
(``log``, ``params``, ``effects``, ``columns``) or, for a log that lacks or spoils a column, that
column's name -- never a server path, never a 500 for anything a user can send.
"""

from __future__ import annotations

import dataclasses
import json
import re
import tempfile
from pathlib import Path
from typing import Any, Literal

from ocp.errors import LogError, ParameterError, SolverError, ThrustshapeError

Payload = dict[str, Any]
Op = Literal["check", "diagnose", "fit", "design"]

PARQUET_MAGIC = b"PAR1"
PARAMS_HELP = "a preset name or the JSON text of a parameter mapping (J, B, ..., optional 'effects')"


def parse_params(text: str) -> str | dict[str, Any]:
    """A preset name, or the JSON mapping in ``text``; validated by building the plant. Never a file."""
    from ocp.model.effects import load_plant
    from ocp.model.params import PRESETS

    source: str | dict[str, Any]
    if text.strip() in PRESETS:
        source = text.strip()
    else:
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ParameterError("params", f"not a preset {list(PRESETS)} and not valid JSON ({exc}); give "
                                           f"{PARAMS_HELP}; files are not read here") from None
        if not isinstance(data, dict):
            raise ParameterError("params", f"must be {PARAMS_HELP}")
        source = data
    try:
        load_plant(source)
    except ThrustshapeError as exc:
        raise _in("params", exc) from None
    return source


def parse_columns(text: str | None) -> dict[str, Any] | None:
    """The column map ``{quantity: "column" | {"column", "unit"}}`` as :mod:`ocp.logs` accepts it."""
    from pydantic import ValidationError

    from ocp.logs import QUANTITIES, UNITS, ColumnSpec

    if text is None or not text.strip():
        return None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise LogError("columns", f"not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise LogError("columns", 'must be a JSON object {quantity: {"column": ..., "unit": ...}}')
    for q, spec in data.items():
        if q not in UNITS:
            raise LogError("columns", f"unknown quantity {q!r}; use {list(QUANTITIES)}")
        try:
            cs = ColumnSpec(column=spec) if isinstance(spec, str) else ColumnSpec.model_validate(spec)
        except ValidationError as exc:
            raise LogError("columns", f"{q}: {exc.errors()[0]['msg']}") from None
        if cs.unit is not None and cs.unit not in UNITS[q]:
            raise LogError("columns", f"{q}: unknown unit {cs.unit!r}; use one of {list(UNITS[q])}")
    return data


READ_FIELDS = ("pole_pairs", "neutral_us", "throttle_range_us", "electrical", "motor", "resample", "negate")


def parse_read(**fields: Any) -> dict[str, Any]:
    """The read options (form fields, ``throttle_range_us`` as ``"min,max"``, ``negate`` comma-separated) validated as
    :class:`ocp.logs.ReadOptions`; errors name the form field. Returns the non-default fields (JSON-ready)."""
    from pydantic import ValidationError

    from ocp.logs import ReadOptions

    data = {k: v for k, v in fields.items() if v is not None}
    text = data.get("throttle_range_us")
    if isinstance(text, str):
        try:
            lo, hi = (float(v) for v in text.split(","))
        except ValueError:
            raise LogError("throttle_range_us", f"{text!r} is not 'min,max' in us (e.g. 1100,1900)") from None
        data["throttle_range_us"] = (lo, hi)
    try:
        opt = ReadOptions(**data)
        opt.half_range_us()
    except ValidationError as exc:
        err = exc.errors()[0]
        raise LogError(str(err["loc"][0]) if err["loc"] else "read", err["msg"]) from None
    return opt.model_dump(mode="json", exclude_defaults=True)


def parse_effects(text: str) -> list[str]:
    """Comma-separated effect names (catalogue names or ``param:<key>`` corrections), at least one."""
    from ocp.identify.candidates import candidate

    names = list(dict.fromkeys(n.strip() for n in text.split(",") if n.strip()))
    if not names:
        raise ParameterError("effects", "give at least one effect name (comma-separated)")
    for n in names:
        try:
            candidate(n)
        except ThrustshapeError as exc:
            raise ParameterError("effects", f"{n!r}: {exc.reason}") from None
    return names


def _in(field: str, exc: ThrustshapeError) -> ThrustshapeError:
    """``exc`` re-raised under the form field ``field`` (its own field kept in the reason)."""
    reason = exc.reason if exc.field == field else f"{exc.field}: {exc.reason}"
    return type(exc)(field, reason)


#: file suffixes read by ocp.logs (".bin" is too common a name to trust: its content decides), and the
#: first bytes that give each format away (issue #13)
LOG_SUFFIXES = {".parquet": ".parquet", ".pq": ".parquet", ".csv": ".csv", ".txt": ".csv", ".xlsx": ".xlsx",
                ".mat": ".mat", ".ulg": ".ulg"}
LOG_MAGIC = ((PARQUET_MAGIC, ".parquet"), (b"ULog", ".ulg"), (b"PK\x03\x04", ".xlsx"), (b"MATLAB", ".mat"),
             (b"\xa3\x95", ".bin"))


def log_suffix(filename: str | None, head: bytes) -> str:
    """The reader's suffix (:data:`LOG_SUFFIXES`): by the upload's file name, else by its first bytes, else CSV."""
    suffix = Path(filename or "").suffix.lower()
    if suffix in LOG_SUFFIXES:
        return LOG_SUFFIXES[suffix]
    return next((sfx for magic, sfx in LOG_MAGIC if head.startswith(magic)), ".csv")


def _read_log(payload: Payload) -> Any:
    """The uploaded log (bytes in ``payload["log"]``) as an :class:`ocp.logs.Log`; errors name the column or ``log``."""
    from ocp.logs import LogKind, ReadOptions, check_size, read_log

    data: bytes = payload["log"]
    name = re.sub(r"[^A-Za-z0-9._ -]+", "_", str(payload.get("filename") or "log"))[:120] or "log"
    steady = payload.get("steady_state")
    kind = None if steady is None else (LogKind.STEADY_STATE if steady else LogKind.TIME_SERIES)
    options = ReadOptions.model_validate(payload.get("read") or {})
    if not data:
        raise LogError("log", "the uploaded file is empty")
    with tempfile.TemporaryDirectory(prefix="thrustshape-log-") as tmp:
        path = Path(tmp) / f"upload{log_suffix(name, data[:8])}"
        path.write_bytes(data)
        try:
            # headers only: refuse a decompression bomb (Parquet, .xlsx, .mat) before decoding it
            check_size(path, max_rows=int(payload["max_samples"]))
            log = read_log(path, payload.get("columns"), kind, options=options)
        except LogError as exc:
            if exc.field in (path.name, str(path)):
                raise LogError("log", exc.reason.replace(str(path), name)) from None
            raise
        except Exception as exc:  # any reader failure (csv, UnicodeDecodeError, pyarrow's errors) is the file's
            fmt = {".parquet": "Parquet", ".xlsx": "Excel .xlsx", ".mat": "MATLAB .mat", ".ulg": "PX4 ULog",
                   ".bin": "ArduPilot DataFlash"}.get(path.suffix, "CSV (UTF-8, header row)")
            detail = f"{type(exc).__name__}: {exc}".replace(str(path), name)[:500]
            raise LogError("log", f"cannot be read as {fmt}: {detail}") from None
    if log.n > int(payload["max_samples"]):
        raise LogError("log", f"{log.n} rows; this server accepts at most {payload['max_samples']}")
    return dataclasses.replace(log, source=name)


def model_check(payload: Payload) -> Payload:
    """Worker task: ``{"op", "log" (bytes), "filename", "params", "columns", "steady_state", "max_samples",
    "effects", "options", "report"}`` -> the core result's ``to_dict()`` (``/fit`` adds ``calibrated_params``;
    ``report`` -> ``{"html": page}``)."""
    from ocp.model.effects import load_plant
    from ocp.model.params import PRESETS

    op: Op = payload["op"]
    log = _read_log(payload)
    source = payload["params"]
    if not (isinstance(source, dict) or source in PRESETS):  # never a path, even from a stored payload
        raise ParameterError("params", f"must be {PARAMS_HELP}")
    try:
        plant = load_plant(source)
    except ThrustshapeError as exc:
        raise _in_params(exc) from None
    options = dict(payload.get("options") or {})
    try:
        return _run(op, plant, log, payload, options)
    except ThrustshapeError as exc:
        if exc.field.startswith("effects.") and op != "fit":  # the params' effects block, not a fit candidate
            raise _in_params(exc) from None
        raise
    except (ArithmeticError, ValueError, RuntimeError) as exc:  # numerics on a degenerate log (e.g. constant)
        raise _blame(plant, log, exc) from None


def _in_params(exc: ThrustshapeError) -> ThrustshapeError:
    """A parameter-mapping error under ``params`` (``effects.x.y`` -> ``params.effects.x.y``)."""
    if exc.field.startswith("effects"):
        return type(exc)(f"params.{exc.field}", exc.reason)
    return _in("params", exc)


def _blame(plant: Any, log: Any, exc: BaseException) -> ThrustshapeError:
    """A numerical failure of the model check: ``params.effects`` when the plant has effects and the nominal
    plant (the same constants without them) checks this log fine, else ``log``."""
    from ocp.identify import CheckOptions, check
    from ocp.model.plant import DCMotorPlant

    detail = f"{type(exc).__name__}: {exc}"[:400]
    if plant.effects:
        try:
            check(DCMotorPlant(plant.params), log, CheckOptions())
        except Exception:  # the log fails without the effects too: it is the log
            pass
        else:
            names = ", ".join(e.name for e in plant.effects)
            return SolverError("params.effects", f"the model check fails with the effects of params ({names}) "
                                                 f"and works without them: {detail}")
    return SolverError("log", f"the model check failed on this log: {detail}")


def _progress(payload: Payload) -> Any:
    """The job's progress callback (``payload["progress"]``: the job store file and the job id), or None."""
    spec = payload.get("progress")
    if not isinstance(spec, dict):
        return None
    from service.checkjobs import ProgressWriter

    return ProgressWriter(str(spec["db"]), str(spec["id"]))


def parse_rivals(text: str | None) -> list[list[str]] | None:
    """Rival explanations for ``/design``: sets separated by ``;``, items of a set by ``,`` (at least two sets)."""
    if text is None or not text.strip():
        return None
    try:
        sets = [parse_effects(part) for part in text.split(";") if part.strip()]
    except ThrustshapeError as exc:
        raise ParameterError("rivals", exc.reason) from None
    if len(sets) < 2:
        raise ParameterError("rivals", "give at least two rival explanations separated by ';' "
                                       "(e.g. 'coulomb_friction;param:B')")
    if len(sets) > 6:
        raise ParameterError("rivals", f"{len(sets)} rivals; at most 6")
    return sets


def _design(plant: Any, log: Any, payload: Payload, options: dict[str, Any], report: Any) -> Payload:
    """Diagnose, then design the experiment that settles it (:func:`ocp.identify.design.design`)."""
    from ocp.identify import DiagnoseOptions, diagnose
    from ocp.identify.design import DesignOptions, design
    from ocp.identify.equations import annotate as with_equations

    res = diagnose(plant, log, DiagnoseOptions(**options), progress=None if report is None else
                   (lambda f: report(0.3 * f)))
    opts = dict(payload.get("design") or {})
    if opts.get("rivals") is not None:
        opts["rivals"] = tuple(tuple(r) for r in opts["rivals"])
    out = design(plant, log, res, DesignOptions(**opts), progress=None if report is None else
                 (lambda f: report(0.3 + 0.7 * f))).to_dict()
    out["diagnosis"] = with_equations(res.to_dict(), log)
    return out


def _run(op: Op, plant: Any, log: Any, payload: Payload, options: dict[str, Any]) -> Payload:
    from ocp.identify import CheckOptions, DiagnoseOptions, FitOptions, check, diagnose, fit
    from ocp.identify.equations import annotate as with_equations

    report = _progress(payload)
    if op == "design":
        return _design(plant, log, payload, options, report)

    if op == "check":
        res = check(plant, log, CheckOptions(**options))
        if payload.get("report"):
            from ocp.identify.report import html_report

            return {"html": html_report(res, log, plant=plant)}
        return with_equations(res.to_dict(), log)
    if op == "diagnose":
        return with_equations(diagnose(plant, log, DiagnoseOptions(**options), progress=report).to_dict(), log)
    fitted = fit(plant, log, list(payload["effects"]), FitOptions(**options))
    out = with_equations(fitted.to_dict(), log)
    out.setdefault("calibrated_params", fitted.calibrated())
    return out

