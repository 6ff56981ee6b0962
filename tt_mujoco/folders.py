"""Output folders: each claimed by one writer, new or an empty one the user named, never one
with files in it, never through a symbolic link, never inside another command's outputs.

A folder is claimed by an exclusive file (:data:`CLAIM_FILE`) that marks its outputs
incomplete until the writer releases it; a command that fails leaves no claimed folder that
holds nothing (:func:`abandon_claims`, from :func:`tt_mujoco.guard.command`). Relative paths
are taken against the folder the command started in (:func:`tt_mujoco.guard.absolute`).
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from tt_mujoco import guard

__all__ = [
    "CLAIM_FILE",
    "METRICS_FILE",
    "OutputError",
    "abandon_claims",
    "claim_folder",
    "enclosing_output",
    "free_name",
    "refuse_link_or_enclosed",
    "release_folder",
    "remove_if_empty",
]


class OutputError(ValueError):
    """An output location that cannot be used; the message names it and says why."""


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
