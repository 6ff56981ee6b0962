"""Writing results: atomic files, JSON, and the time series on disk (the output folders
themselves are :mod:`tt_mujoco.folders`, re-exported here).

Every application (run, sweep, paper suite, validation, re-rendering) writes through here, so
they follow one rule: outputs go to a new folder, or an empty one named by the user, never into
one with files in it; a file is written under a temporary name in its folder and renamed, so a
reader (or a crash) sees the complete file or none; a file that exists is never replaced
unless the caller owns it (:func:`atomic_write` replaces, :func:`publish_new` never does).
"""

from __future__ import annotations

import contextlib
import csv
import dataclasses
import io
import json
import math
import os
import re
import sys
import tempfile
import warnings
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from tt_mujoco.folders import (
    CLAIM_FILE,
    METRICS_FILE,
    OutputError,
    abandon_claims,
    claim_folder,
    enclosing_output,
    free_name,
    refuse_link_or_enclosed,
    release_folder,
    remove_if_empty,
)

__all__ = [
    "CLAIM_FILE",
    "METRICS_FILE",
    "OutputError",
    "abandon_claims",
    "atomic_write",
    "claim_folder",
    "enclosing_output",
    "free_name",
    "json_default",
    "json_safe",
    "publish_new",
    "read_regular",
    "read_timeseries",
    "refuse_link_or_enclosed",
    "release_folder",
    "remove_if_empty",
    "run_timeseries_file",
    "save_figure",
    "temporary_beside",
    "timeseries_csv",
    "write_json",
    "write_timeseries",
]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def temporary_beside(path: Path, suffix: str = ".tmp"):
    """A fresh, uniquely named temporary file in ``path``'s folder, removed unless renamed."""
    fd, name = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    tmp = Path(name)
    try:
        os.close(fd)
        tmp.chmod(0o666 & ~_umask())  # mkstemp made it private; give it a normal file's mode
        yield tmp
    finally:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()


def atomic_write(path: Path, data: str | bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder, flushed to disk,
    then renamed over ``path``: a reader (or a crash) sees no file or the complete one."""
    path = Path(path)
    with temporary_beside(path) as tmp:
        with open(tmp, "wb") as handle:
            handle.write(data.encode() if isinstance(data, str) else data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)


def publish_new(made: Path, out: Path) -> Path:
    """Move the finished file ``made`` to ``out`` atomically, never replacing an existing
    ``out`` (FileExistsError)."""
    made, out = Path(made), Path(out)
    made.chmod(0o666 & ~_umask())  # a mkstemp file is private; give it a normal file's mode
    try:
        os.link(made, out)  # fails if out exists: no race between a check and the move
    except FileExistsError:
        raise FileExistsError(f"{out} exists; it is not overwritten") from None
    except OSError:  # a file system without hard links
        if out.exists():
            raise FileExistsError(f"{out} exists; it is not overwritten") from None
        os.replace(made, out)
        return out
    made.unlink()
    return out


def save_figure(fig, path: Path, dpi: float) -> Path:
    """Write a matplotlib figure as PNG to ``path`` atomically."""
    path = Path(path)
    with temporary_beside(path, suffix=".tmp.png") as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
        os.replace(tmp, path)
    return path


def json_default(obj):
    """``json.dumps(default=...)`` for numpy scalars and arrays and paths."""
    if isinstance(obj, np.floating | np.integer):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def json_safe(value):
    """``value`` with numpy types made plain, and non-finite floats and integers beyond a float
    made None (strict JSON that :func:`parse_strict_json` reads back)."""
    if isinstance(value, Mapping):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_safe(value.tolist())
    if isinstance(value, np.integer | bool | np.bool_):
        return value if isinstance(value, bool) else int(value)
    if isinstance(value, float | np.floating):
        return float(value) if np.isfinite(value) else None
    if isinstance(value, int) and abs(value) > _FLOAT_MAX:  # what the strict reader refuses
        return None
    return value


#: The largest float: an integer beyond it is not read back (:func:`parse_strict_json`).
_FLOAT_MAX = sys.float_info.max


def timeseries_csv(ts: Mapping[str, np.ndarray], columns) -> str:
    """The time series as CSV text in ``columns`` order, every float with full precision."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    for row in zip(*(ts[c] for c in columns), strict=True):
        writer.writerow([repr(float(v)) for v in row])
    return buf.getvalue()


def arrow_float64(values):
    """``values`` as a float64 ``pyarrow.Array``, sharing the array's memory where it can.

    Built from its buffer, not by ``pa.array``, which imports pandas on first use (about
    0.3 s of every run that writes Parquet).
    """
    import pyarrow as pa

    values = np.ascontiguousarray(values, dtype=np.float64)
    return pa.Array.from_buffers(pa.float64(), len(values), [None, pa.py_buffer(values)])


def write_timeseries(path: Path, ts: Mapping[str, np.ndarray], columns, units=None) -> None:
    """The time series to ``path`` atomically: Parquet (``.parquet``: float64 columns, the
    units in the schema's metadata, zstd compression) or CSV (``.csv``: full precision)."""
    path = Path(path)
    if path.suffix == ".csv":
        atomic_write(path, timeseries_csv(ts, columns))
        return
    import pyarrow as pa  # only where Parquet is written or read
    import pyarrow.parquet as pq

    fields = [
        pa.field(c, pa.float64(), metadata={"unit": (units or {}).get(c, "")}) for c in columns
    ]
    table = pa.Table.from_arrays([arrow_float64(ts[c]) for c in columns], schema=pa.schema(fields))
    table = table.replace_schema_metadata({"tt_mujoco": json.dumps({"units": units or {}})})
    with temporary_beside(path, suffix=".tmp.parquet") as tmp:
        # no dictionary: float columns seldom repeat, and trying one doubled the time
        pq.write_table(table, tmp, compression="zstd", use_dictionary=False)
        os.replace(tmp, path)


#: A run folder's own copy of its reference path (columns x, y in m): what render and compare
#: draw, never a CSV file that may have changed since the run.
REFERENCE_FILE = "reference_path.parquet"


def run_timeseries_file(run_dir: Path) -> Path:
    """A run folder's time series: ``timeseries.parquet`` when there is anything by that name
    (a link to nothing too: the caller refuses what is not a file), else the path of
    ``timeseries.csv`` (which the caller checks for)."""
    parquet = Path(run_dir) / "timeseries.parquet"
    return parquet if os.path.lexists(parquet) else parquet.with_suffix(".csv")


def read_timeseries(path) -> dict[str, np.ndarray]:
    """A time series file (``.parquet``, or ``.csv``: header row, then numbers; a UTF-8 byte
    order mark is read past) as column name -> 1-D array. A column without a name, or a name
    given twice, is a ``ValueError`` (which of the two would be read is a guess)."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow as pa
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        names = _column_names(path, table.column_names)
        for name, kind in zip(names, table.schema.types, strict=True):
            # numbers only: text that happens to spell numbers is a damaged file, not data
            if not (pa.types.is_floating(kind) or pa.types.is_integer(kind)):
                raise ValueError(f"{path}: column {name!r} holds {kind}, not numbers")
        return {name: table.column(j).to_numpy().astype(float) for j, name in enumerate(names)}
    with path.open(newline="", encoding="utf-8-sig") as f:
        header = next(csv.reader(f), None)
    if not header:
        raise ValueError(f"{path} is empty: a time series needs a header row")
    if len(header) == 1 and any(mark in header[0] for mark in ";\t|"):
        raise ValueError(
            f"{path}: its header {header[0][:60]!r} is one column: a CSV file's columns are "
            "separated by commas"
        )
    names = _column_names(path, header)
    with warnings.catch_warnings():  # a header and no rows: no columns' rows, said so below
        warnings.simplefilter("ignore", UserWarning)
        try:
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
        except ValueError as err:  # NumPy counts data rows from 0: said as the file's lines
            found = re.search(r"string (.*) to float64 at row (\d+), column (\d+)", str(err))
            ragged = re.search(r"columns changed from (\d+) to (\d+) at row (\d+)", str(err))
            if ragged is not None:  # NumPy's advice (its own `usecols`) is no option here
                was, now, row = (int(g) for g in ragged.groups())
                raise ValueError(
                    f"{path}: row {row + 1} has {now} values where the rows before have {was}"
                ) from None
            if found is None:
                raise
            row, col = int(found.group(2)), int(found.group(3))
            column = f"column {names[col - 1]!r}" if col <= len(names) else f"column {col}"
            raise ValueError(
                f"{path}: {column} row {row + 2} is {found.group(1)}, not a number"
            ) from None
    if data.size == 0:
        return {name: np.zeros(0) for name in names}
    if data.shape[1] != len(header):
        raise ValueError(f"{path} has {len(header)} header names but {data.shape[1]} columns")
    return {name: data[:, j].copy() for j, name in enumerate(names)}


def _column_names(path: Path, header) -> list[str]:
    """The header's names, stripped; a ValueError for one empty or given twice."""
    names = [str(name).strip() for name in header]
    for j, name in enumerate(names):
        if not name:
            raise ValueError(f"{path}: column {j + 1} has no name")
        if name in names[:j]:
            raise ValueError(
                f"{path}: column {name!r} is given twice (columns {names.index(name) + 1} and "
                f"{j + 1}): which to read is a guess"
            )
    return names


def shown_json(value) -> str:
    """``value`` as JSON, cut to 40 characters, for a message."""
    text = json.dumps(value, default=repr)
    return text if len(text) <= 40 else text[:37] + "..."


@dataclasses.dataclass(frozen=True)
class JsonField:
    """A declared field of a JSON document read back: its dotted path, the JSON types it may
    hold and, in words, what it holds (for the message that refuses it)."""

    path: str
    types: tuple[type, ...]
    what: str
    required: bool = False

    def why_not(self, value) -> str:
        """Why ``value`` cannot be this field, or ""."""
        if isinstance(value, bool) and bool not in self.types:
            return f"holds {value!r}, not {self.what}"
        if not isinstance(value, self.types):
            return f"holds {shown_json(value)}, not {self.what}"
        if int in self.types and isinstance(value, int) and value < 0:
            return f"holds {value}, not {self.what}"
        return ""


_MISSING = object()


def lookup(doc, path: str, default=None):
    """The value at dotted ``path`` of nested tables, or ``default``."""
    value = doc
    for key in path.split("."):
        if not isinstance(value, Mapping) or key not in value:
            return default
        value = value[key]
    return value


def check_fields(doc: Mapping, fields) -> str:
    """Why ``doc`` breaks one of the declared ``fields`` (naming it), or ""."""
    for field in fields:
        value = lookup(doc, field.path, _MISSING)
        if value is _MISSING:
            if field.required:
                return f"{field.path} is missing: it holds {field.what}"
            continue
        why = field.why_not(value)
        if why:
            return f"{field.path} {why}"
    return ""


def parse_strict_json(text: str):
    """``text`` as strict JSON: no NaN or infinities, no number beyond a float, no key twice.

    Raises
    ------
    ValueError
        Saying what is not strict JSON (``json.JSONDecodeError`` with its line and column).
    """

    def strict_float(number: str) -> float:
        value = float(number)
        if not math.isfinite(value):
            raise ValueError(f"the number {number[:40]} is beyond a float")
        return value

    def strict_int(number: str) -> int:
        value = int(number)
        try:
            float(value)
        except OverflowError:
            raise ValueError(f"the number {number[:40]}... is beyond a float") from None
        return value

    def no_constant(name: str):
        raise ValueError(f"{name} is not JSON (strict JSON has no NaN or infinities)")

    def unique(pairs):
        keys = [k for k, _ in pairs]
        twice = sorted({k for k in keys if keys.count(k) > 1})
        if twice:
            raise ValueError(f"the key {twice[0]!r} is given twice")
        return dict(pairs)

    try:
        return json.loads(
            text,
            parse_float=strict_float,
            parse_int=strict_int,
            parse_constant=no_constant,
            object_pairs_hook=unique,
        )
    except RecursionError:
        raise ValueError("it is nested too deeply") from None


def read_regular(path, shown: str) -> bytes:
    """The bytes of the regular file ``path``: what a file read back may be. A FIFO, a device
    or a folder is refused before it is opened (``/dev/zero`` would be read for ever, a FIFO
    waits for a writer), with a ValueError naming it as ``shown``; ``FileNotFoundError`` is
    raised as it is, for a reader to which a missing file means something."""
    import stat

    try:
        mode = os.stat(path).st_mode
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
            raise ValueError(f"{shown} cannot be read: it is {kind}")
        with open(path, "rb") as handle:
            return handle.read()
    except FileNotFoundError:
        raise
    except OSError as err:
        raise ValueError(f"{shown} cannot be read: {err.strerror}") from None


def read_utf8(path, shown: str) -> str:
    """The text of file ``path``; a ValueError naming it as ``shown`` when it cannot be read
    (:func:`read_regular`) or is not UTF-8 (with the first bad byte): the one way a text file
    read back is opened. A leading byte-order mark (what Windows editors write) is dropped, as
    the CSV readers drop it."""
    try:
        data = read_regular(path, shown)
    except FileNotFoundError as err:
        raise ValueError(f"{shown} cannot be read: {err.strerror}") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise ValueError(
            f"{shown} cannot be read: it is not UTF-8 text (byte {err.start})"
        ) from None


def read_strict_json(path):
    """The strict JSON file ``path`` (:func:`parse_strict_json`).

    Raises
    ------
    ValueError
        Naming the file: unreadable, not UTF-8, or not strict JSON.
    """
    text = read_utf8(path, str(path))
    try:
        return parse_strict_json(text)
    except json.JSONDecodeError as err:
        raise ValueError(f"{path} is not JSON: {err}") from None
    except ValueError as err:
        raise ValueError(f"{path} is not strict JSON: {err}") from None


def read_toml(path, what: str) -> dict:
    """The TOML file ``path`` as a table: the one reader of every TOML file (scenario files,
    sweep specifications, world files, the copies a run keeps).

    Raises
    ------
    ValueError
        Naming ``what`` and the file: unreadable, not UTF-8, not valid TOML (with its line), or
        nested too deeply.
    """
    import tomllib

    shown = f"{what} {str(path)!r}"
    text = read_utf8(path, shown)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise ValueError(f"{shown} is not valid TOML: {err}") from None
    except RecursionError:
        raise ValueError(
            f"{shown} is nested too deeply: a TOML file here is keys and a few tables"
        ) from None


def write_json(path: Path, doc, strict: bool = False) -> None:
    """``doc`` as indented JSON, atomically; ``strict`` turns NaN and infinities into null."""
    if strict:
        text = json.dumps(json_safe(doc), indent=2, allow_nan=False)
    else:
        text = json.dumps(doc, indent=2, default=json_default)
    atomic_write(path, text + "\n")
