"""Files -> named numeric columns: CSV (``pyarrow.csv``), Parquet, Excel ``.xlsx`` (``openpyxl``,
optional extra ``[xlsx]``) and MATLAB ``.mat`` (``scipy.io``, v4-v7; v7.3 is HDF5 and refused).

Every reader returns ``{header: values (N,) float}``; non-numeric columns are dropped, empty cells
are NaN. Title lines above the header (a vendor workbook saved as CSV) are skipped: the header is the
first line in which at least two cells are headers thrustshape recognises (:mod:`ocp.logs.headers`).
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any

import numpy as np

from ocp.errors import LogError
from ocp.logs.bounds import check_parquet_size, check_size
from ocp.logs.headers import parse_header

_SCAN_LINES = 30


def _is_number(type_name: str) -> bool:
    return type_name.startswith(("int", "uint", "float", "double", "halffloat"))


def _read_parquet(p: Path) -> dict[str, np.ndarray]:
    """Numeric columns of a Parquet file (its footer checked first: :func:`check_parquet_size`)."""
    import pyarrow.parquet as pq

    check_parquet_size(p)
    tab = pq.read_table(p)
    return {str(c): np.asarray(tab.column(c).to_numpy(zero_copy_only=False), dtype=float)
            for c in tab.column_names if tab.schema.field(c).type.num_fields == 0
            and _is_number(str(tab.schema.field(c).type))}


def _header_line(lines: list[str], delimiter: str) -> int:
    """Index of the header line: the first with two recognised headers (0 when none is)."""
    for k, line in enumerate(lines[:_SCAN_LINES]):
        cells = [c.strip().strip('"') for c in line.split(delimiter)]
        if sum(parse_header(c) is not None for c in cells if c) >= 2:
            return k
    return 0


def _read_csv(p: Path) -> dict[str, np.ndarray]:
    import pyarrow as pa
    import pyarrow.compute as pc
    from pyarrow import csv

    raw = p.read_bytes()
    text_head = raw[:65536].decode("utf-8-sig", errors="replace").splitlines()
    if not text_head:
        raise LogError(p.name, "no data rows")
    first = text_head[0]
    delimiter = ";" if first.count(";") > first.count(",") else ("\t" if "\t" in first and "," not in first else ",")
    skip = _header_line(text_head, delimiter)
    body = raw[3:] if raw.startswith(b"\xef\xbb\xbf") else raw
    try:
        tab = csv.read_csv(io.BytesIO(body), read_options=csv.ReadOptions(skip_rows=skip),
                           parse_options=csv.ParseOptions(delimiter=delimiter),
                           convert_options=csv.ConvertOptions(strings_can_be_null=True))
    except pa.ArrowInvalid as exc:
        raise LogError(p.name, f"cannot be read as CSV: {exc}") from None
    if tab.num_rows < 1:
        raise LogError(p.name, "no data rows")
    out: dict[str, np.ndarray] = {}
    for name, col in zip(tab.column_names, tab.columns, strict=True):
        if pa.types.is_string(col.type) or pa.types.is_large_string(col.type):
            try:
                col = pc.cast(pc.utf8_trim_whitespace(col), pa.float64())
            except (pa.ArrowInvalid, pa.ArrowNotImplementedError):
                continue  # a text column: ignored unless it is needed
        elif pa.types.is_null(col.type):
            col = pa.chunked_array([pa.nulls(len(col), pa.float64())])
        elif not (pa.types.is_integer(col.type) or pa.types.is_floating(col.type)):
            continue
        out[name.strip()] = np.asarray(pc.fill_null(pc.cast(col, pa.float64()), float("nan")).to_numpy(), float)
    return out


def _cell_number(v: Any) -> float:
    if isinstance(v, bool) or v is None:
        return float("nan")
    if isinstance(v, int | float):
        return float(v)
    try:
        return float(str(v).strip())
    except ValueError:
        return float("nan")


def _sheet_columns(rows: list[tuple[Any, ...]]) -> dict[str, np.ndarray]:
    for k, row in enumerate(rows[:_SCAN_LINES]):
        cells = [str(c).strip() for c in row if isinstance(c, str)]
        if sum(parse_header(c) is not None for c in cells) < 2:
            continue
        header = [str(c).strip() if c is not None else "" for c in row]
        out = {}
        for j, name in enumerate(header):
            vals = np.array([_cell_number(r[j] if j < len(r) else None) for r in rows[k + 1:]], dtype=float)
            if name and np.any(np.isfinite(vals)):
                out[name] = vals
        last = max((int(np.flatnonzero(np.isfinite(v))[-1]) for v in out.values()), default=-1)
        return {n: v[:last + 1] for n, v in out.items()}
    return {}


def _read_xlsx(p: Path) -> dict[str, np.ndarray]:
    check_size(p)
    try:
        import openpyxl
    except ImportError:
        raise LogError(p.name, "reading .xlsx needs openpyxl: pip install 'thrustshape[xlsx]' "
                               "(or save the sheet as CSV)") from None
    try:
        wb = openpyxl.load_workbook(p, read_only=True, data_only=True)
    except Exception as exc:  # zipfile/openpyxl errors on a broken workbook are the file's
        raise LogError(p.name, f"cannot be read as .xlsx: {type(exc).__name__}: {exc}") from None
    try:
        for ws in wb.worksheets:
            cols = _sheet_columns([tuple(r) for r in ws.iter_rows(values_only=True)])
            if cols:
                return cols
    finally:
        wb.close()
    raise LogError(p.name, "no sheet has a header row with recognised columns (e.g. 'PWM (µs)', 'RPM', 'Force (N)')")


def _read_mat(p: Path) -> dict[str, np.ndarray]:
    from scipy import io as sio

    check_size(p)
    try:
        data = sio.loadmat(p, squeeze_me=True, simplify_cells=True)
    except NotImplementedError:
        raise LogError(p.name, "MATLAB v7.3 (HDF5) files are not read; save with save(..., '-v7')") from None
    except (ValueError, TypeError, OSError) as exc:
        raise LogError(p.name, f"cannot be read as a MATLAB .mat file: {exc}") from None
    out: dict[str, np.ndarray] = {}

    def take(name: str, v: Any) -> None:
        a = np.asarray(v)
        if a.dtype.kind in "iuf" and a.ndim == 1 and a.size > 1:
            out[name] = a.astype(float)

    for k, v in data.items():
        if k.startswith("__"):
            continue
        if isinstance(v, dict):  # one struct level: log.t, log.rpm, ...
            for f, fv in v.items():
                take(str(f), fv)
        else:
            take(k, v)
    return out


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV, Parquet, ``.xlsx`` or ``.mat`` file (by suffix; anything else is CSV)."""
    p = Path(path)
    if not p.is_file():
        raise LogError(str(path), "no such file")
    suffix = p.suffix.lower()
    if suffix in (".parquet", ".pq"):
        return _read_parquet(p)
    if suffix in (".xlsx", ".xlsm"):
        return _read_xlsx(p)
    if suffix == ".mat":
        return _read_mat(p)
    return _read_csv(p)
