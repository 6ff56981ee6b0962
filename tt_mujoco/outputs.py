"""Writing results: output folders, atomic files, JSON, and the time series on disk.

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

from tt_mujoco import guard

__all__ = [
    "METRICS_FILE",
    "OutputError",
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


class OutputError(ValueError):
    """An output location that cannot be used; the message names it and says why."""


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


def free_name(base: Path) -> Path:
    """``base`` if nothing is there, else the first free ``base-2``, ``base-3``, ..."""
    path, i = Path(base), 1
    while path.exists() or path.is_symlink():
        i += 1
        path = Path(base).with_name(f"{Path(base).name}-{i}")
    return path


#: The file that claims an output folder for one writer. It is created exclusively (two runs
#: started into one folder at once: one gets it, the other is refused) and removed when the
#: outputs are complete, so a folder that still has it holds an interrupted run's outputs.
CLAIM_FILE = ".in-progress"
#: A finished run's record, written last: a folder with it holds a run's outputs.
METRICS_FILE = "metrics.json"


#: The folders this process claimed and has not released, with whether it made them.
_CLAIMED: dict[Path, bool] = {}


def abandon_claims() -> list[Path]:
    """After a command failed (:func:`tt_mujoco.guard.command`): every folder it claimed and
    did not release is removed where it holds nothing but the claim (a folder the user named
    is left as it was); one holding outputs keeps them, labelled incomplete by the claim.
    Returns those folders."""
    claimed = list(_CLAIMED)
    for out, created in list(_CLAIMED.items()):
        _CLAIMED.pop(out, None)
        with contextlib.suppress(OSError):
            if {p.name for p in out.iterdir()} <= {CLAIM_FILE}:
                if created:
                    remove_if_empty(out)
                else:
                    release_folder(out)
    return claimed


def _claim(out: Path, option: str, created: bool) -> None:
    try:
        fd = os.open(out / CLAIM_FILE, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW)
    except FileExistsError:
        raise OutputError(
            f"{option} {str(out)!r} is being written by another run: outputs are never mixed; "
            "name a new folder"
        ) from None
    except OSError as err:
        if created:
            remove_if_empty(out)
        raise OutputError(f"{option} {str(out)!r} cannot be written: {err.strerror}") from None
    _CLAIMED[out.absolute()] = created
    with os.fdopen(fd, "w") as handle:
        handle.write(
            f"claimed by process {os.getpid()}: while this file is here the outputs in this "
            "folder are incomplete (a run in progress, or one that was interrupted)\n"
        )


def enclosing_output(path: Path) -> Path | None:
    """The folder of outputs that ``path`` lies inside, or None: the nearest parent holding a
    run's ``metrics.json`` or the claim of a writer (finished outputs are a record, and
    unfinished ones are another writer's)."""
    for parent in Path(path).resolve().parents:
        if (parent / METRICS_FILE).is_file() or (parent / CLAIM_FILE).exists():
            return parent
    return None


def refuse_link_or_enclosed(out: Path, option: str = "--out") -> None:
    """Refuse an output folder ``out`` that is a symbolic link (outputs are never written
    through one) or lies inside another command's outputs (:func:`enclosing_output`)."""
    if out.is_symlink():
        target = os.readlink(out)
        state = "" if out.exists() else ", which does not exist"
        raise OutputError(
            f"{option} {str(out)!r} is not allowed: it is a symbolic link (to {target!r}{state}) "
            "and outputs are never written through a link; name the folder itself, or a new one"
        )
    inside = enclosing_output(out)
    if inside is not None:
        raise OutputError(
            f"{option} {str(out)!r} is not allowed: it lies inside {str(inside)!r}, the "
            "outputs of another run or command, which are never changed; name a folder "
            "outside it"
        )


def release_folder(out: Path) -> None:
    """Mark ``out``'s outputs complete (remove the claim :func:`claim_folder` made)."""
    _CLAIMED.pop(Path(out).absolute(), None)
    with contextlib.suppress(FileNotFoundError):
        (Path(out) / CLAIM_FILE).unlink()


def claim_folder(out: Path | None, default_base: Path, option: str = "--out") -> tuple[Path, bool]:
    """A new, writable output folder, or an existing empty one named by the user, claimed for
    this writer until :func:`release_folder` (see :data:`CLAIM_FILE`).

    Parameters
    ----------
    out : Path or None
        The user's folder; None for a new one named after ``default_base`` (``-2``, ``-3``,
        ... appended while taken; created without ``exist_ok``, so parallel runs never share).
    default_base : Path
    option : str
        The option that named ``out``, for messages.

    Returns
    -------
    (Path, bool)
        The folder and whether this call created it (only such a folder is removed again when
        the work is abandoned).

    Raises
    ------
    OutputError
        ``out`` holds files, is not a folder, is a symbolic link, lies inside another
        command's outputs, or cannot be created or written.
    """
    # absolute now: a user's code that changes the working folder moves no output
    default_base = guard.absolute(default_base)
    if out is None:
        inside = enclosing_output(default_base)
        if inside is not None:  # run from inside a finished run's folder
            raise OutputError(
                f"the new folder {str(default_base)!r} would lie inside {str(inside)!r}, the "
                f"outputs of another run or command, which are never changed; name a folder "
                f"outside it with {option}"
            )
        for _ in range(1000):
            path = free_name(default_base)
            try:
                path.mkdir(parents=True)
            except FileExistsError:
                continue  # taken between the look and the mkdir: try the next name
            except OSError as err:
                raise OutputError(
                    f"output folder {str(path)!r} cannot be created: {err.strerror}"
                ) from None
            _claim(path, "output folder", created=True)
            return path, True
        raise OutputError(f"no free output folder name for {str(default_base)!r}")
    out = guard.absolute(out)
    try:
        str(out).encode("utf-8")
    except UnicodeEncodeError:
        raise OutputError(
            f"{option} {str(out)!r} is not allowed: the name has bytes that are not UTF-8, "
            "which the time series' file format cannot record; use a UTF-8 name"
        ) from None
    refuse_link_or_enclosed(out, option)
    if out.exists() and (not out.is_dir() or any(out.iterdir())):
        raise OutputError(
            f"{option} {str(out)!r} already exists and is not an empty folder: outputs are "
            "never overwritten; name a new folder"
        )
    created = not out.exists()
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise OutputError(f"{option} {str(out)!r} cannot be written: {err.strerror}") from None
    _claim(out, option, created)
    return out, created


def remove_if_empty(out: Path) -> None:
    """Release ``out`` and remove it if it is then an empty folder (what an abandoned run
    leaves)."""
    release_folder(out)
    with contextlib.suppress(OSError):
        if out.is_dir() and not any(out.iterdir()):
            out.rmdir()


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
    """A run folder's time series: ``timeseries.parquet`` when it is there, else the path of
    ``timeseries.csv`` (which the caller checks for)."""
    parquet = Path(run_dir) / "timeseries.parquet"
    return parquet if parquet.is_file() else parquet.with_suffix(".csv")


def read_timeseries(path) -> dict[str, np.ndarray]:
    """A time series file (``.parquet``, or ``.csv``: header row, then numbers; a UTF-8 byte
    order mark is read past) as column name -> 1-D array. A column without a name, or a name
    given twice, is a ``ValueError`` (which of the two would be read is a guess)."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq

        table = pq.read_table(path)
        names = _column_names(path, table.column_names)
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
