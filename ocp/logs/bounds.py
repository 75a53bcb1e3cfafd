"""What a compressed table file may expand to, checked BEFORE it is decoded (a small upload can hold GBs).

Parquet announces its rows and uncompressed bytes in its footer (:func:`check_parquet_size`);
an ``.xlsx`` workbook is a zip whose central directory lists every member's uncompressed size; a MATLAB v5
``.mat`` file is a sequence of elements whose sizes are in their tags, except zlib-compressed ones
(``miCOMPRESSED``), which are inflated here in bounded chunks and thrown away, counting, until the budget is
spent. v4 files are not compressed (the file size bounds them); v7.3 files are HDF5 and refused by the reader.

The budget is per row of the log: :data:`BYTES_PER_ROW` times the most rows the caller accepts (the service's
``max_log_samples``; the readers' own default :data:`DEFAULT_MAX_ROWS`).
"""

from __future__ import annotations

import struct
import zipfile
import zlib
from pathlib import Path
from typing import BinaryIO

from ocp.errors import LogError

#: uncompressed bytes one row may take: 64 float64 columns (Parquet, MATLAB); an .xlsx sheet's XML spends about
#: 50 bytes on a numeric cell (``<c r="AB12345"><v>-0.0123456789</v></c>``), so 512 bytes are ~10 columns
BYTES_PER_ROW = {".parquet": 8 * 64, ".mat": 8 * 64, ".xlsx": 512}
_CHUNK = 1 << 20  # inflate at most this many bytes at a time
_MI_COMPRESSED = 15

#: what a Parquet log may announce in its footer before any of it is decoded (a small file can expand to GBs)
PARQUET_LIMITS = {"rows": 10_000_000, "columns": 1_000, "bytes": 1 << 30}
DEFAULT_MAX_ROWS = PARQUET_LIMITS["rows"]


def check_parquet_size(path: str | Path, max_rows: int = PARQUET_LIMITS["rows"],
                       max_columns: int = PARQUET_LIMITS["columns"], max_bytes: int = PARQUET_LIMITS["bytes"]) -> None:
    """Refuse (:class:`LogError` ``log``) a Parquet file whose metadata announces more than ``max_rows`` rows,
    ``max_columns`` columns or ``max_bytes`` uncompressed bytes: only the footer is read, nothing decoded."""
    import pyarrow.parquet as pq

    meta = pq.ParquetFile(path).metadata
    size = sum(meta.row_group(i).total_byte_size for i in range(meta.num_row_groups))
    for what, n, top in (("rows", meta.num_rows, max_rows), ("columns", meta.num_columns, max_columns),
                         ("uncompressed bytes", size, max_bytes)):
        if n > top:
            raise LogError("log", f"the Parquet file announces {n} {what}; at most {top} accepted")


def check_size(path: str | Path, max_rows: int = DEFAULT_MAX_ROWS) -> None:
    """Refuse (:class:`LogError` ``log``) a Parquet, ``.xlsx`` or ``.mat`` file (by suffix) that would expand to
    more than ``max_rows`` rows' worth of bytes (:data:`BYTES_PER_ROW`); other formats are not compressed, and
    their file size is their bound. Reads headers only, and inflates at most the budget plus one chunk."""
    p = Path(path)
    suffix = {".pq": ".parquet", ".xlsm": ".xlsx"}.get(p.suffix.lower(), p.suffix.lower())
    if suffix not in BYTES_PER_ROW:
        return
    budget = max_rows * BYTES_PER_ROW[suffix]
    if suffix == ".parquet":
        check_parquet_size(p, max_rows=max_rows, max_bytes=budget)
    elif suffix == ".xlsx":
        _check_zip(p, budget)
    else:
        _check_mat(p, budget)


def _refuse(what: str, budget: int) -> LogError:
    return LogError("log", f"the {what} expands to more than {budget} bytes (about {budget / 2**20:.0f} MiB) "
                           "once decompressed; that is more rows than accepted")


def _check_zip(p: Path, budget: int) -> None:
    """Sum of the members' uncompressed sizes from the zip's central directory (nothing inflated)."""
    try:
        with zipfile.ZipFile(p) as z:
            total = sum(info.file_size for info in z.infolist())
    except (zipfile.BadZipFile, OSError) as exc:
        raise LogError("log", f"cannot be read as .xlsx (a zip archive): {exc}") from None
    if total > budget:
        raise _refuse(".xlsx workbook", budget)


def _check_mat(p: Path, budget: int) -> None:
    """Walk a v5 ``.mat`` file's top-level elements: tag sizes, and compressed elements inflated and counted."""
    with p.open("rb") as f:
        header = f.read(128)
        if len(header) < 128 or header[126:128] not in (b"IM", b"MI"):
            return  # v4 (uncompressed: its file size bounds it) or not a .mat file: the reader says which
        endian = "<" if header[126:128] == b"IM" else ">"
        total = 0
        while True:
            tag = f.read(8)
            if len(tag) < 8:
                return
            dtype, nbytes = struct.unpack(endian + "II", tag)
            if dtype >> 16:  # a small data element packs its size into the tag
                continue
            if dtype != _MI_COMPRESSED:
                total += nbytes
                f.seek(nbytes + (-nbytes) % 8, 1)
            else:
                total += _inflated_size(f, nbytes, budget - total)
            if total > budget:
                raise _refuse("MATLAB file", budget)


def _inflated_size(f: BinaryIO, nbytes: int, left: int) -> int:
    """Bytes the next ``nbytes`` of zlib data in ``f`` inflate to (counting stops past ``left``; nothing is kept)."""
    inflate, size, remaining = zlib.decompressobj(), 0, nbytes
    while remaining > 0 and size <= left:
        data = f.read(min(remaining, _CHUNK))
        if not data:
            break
        remaining -= len(data)
        try:
            while data and size <= left:
                size += len(inflate.decompress(data, _CHUNK))
                data = inflate.unconsumed_tail
        except zlib.error as exc:
            raise LogError("log", f"cannot be read as a MATLAB .mat file: a compressed element is corrupt ({exc})") \
                from None
    return size
