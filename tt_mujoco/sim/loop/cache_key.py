"""The key of the compiled-code cache: which version of the sources a cached kernel is.

:func:`source_digest` hashes what the compiled code depends on; working it out imports every
module the kernel compiles. :func:`digest_by_stamp` finds it instead by a stamp of the files'
sizes and times (:func:`sources_stamp`), once a process has worked it out for them.
"""

from __future__ import annotations

import functools
import hashlib
import sys
from pathlib import Path

from tt_mujoco.outputs import atomic_write

__all__ = ["digest_by_stamp", "file_key", "source_digest", "sources_stamp"]


@functools.cache
def digest_by_stamp(stamps: Path) -> str:
    """:func:`source_digest`, looked up by :func:`sources_stamp` in ``stamps`` where a process
    has worked it out for the same files before: working it out imports every module the
    kernel compiles and reads their code (a tenth of a second, paid by every single run as it
    exits, :func:`tt_mujoco.sim.loop.compiled.ask_for_cache`), where the stamp only lists the
    files' sizes and times."""
    known = stamps / sources_stamp()
    try:
        digest = known.read_text().strip()
    except OSError:
        digest = ""
    if len(digest) == 16 and all(c in "0123456789abcdef" for c in digest):
        return digest
    digest = source_digest()
    try:
        stamps.mkdir(parents=True, exist_ok=True)
        atomic_write(known, digest + "\n")
    except OSError:
        pass  # a read-only cache: worked out again next time
    return digest


@functools.cache
def sources_stamp() -> str:
    """A key of every file :func:`source_digest` reads, by name, size and modification time:
    every Python file of the package and its controllers (a superset of the kernel's), and the
    interpreter, the machine and the installed numba, llvmlite and MuJoCo. An edit changes
    it, and the digest is worked out again."""
    import platform
    from importlib.util import find_spec

    parts = [sys.version, platform.machine()]
    for name in ("numba", "llvmlite", "mujoco"):
        spec = find_spec(name)  # found, not imported
        parts.append(file_key(Path(spec.origin)) if spec and spec.origin else f"{name}: none")
    for package in ("tt_mujoco", "tt_mujoco.controllers"):
        for folder in find_spec(package).submodule_search_locations:
            parts += [file_key(f) for f in sorted(Path(folder).rglob("*.py"))]
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:32]


def file_key(path: Path) -> str:
    """A file by its resolved path, size and modification time."""
    stat = path.stat()
    return f"{path.resolve()} {stat.st_size} {stat.st_mtime_ns}"


@functools.cache
def source_digest() -> str:
    """A hash of what the compiled code depends on: the interpreter, the machine, numba's,
    llvmlite's and MuJoCo's versions, every file the kernel compiles
    (:func:`tt_mujoco.sim.loop.kernel_sources.source_files`, that module's, this file,
    :mod:`~tt_mujoco.sim.loop.compiled`, the kernel's and its machine code's) and the
    built-in laws in their order (a law's index is its kind)."""
    import platform
    from importlib import metadata

    from tt_mujoco.sim.loop import kernel_sources

    versions = [metadata.version(name) for name in ("numba", "llvmlite", "mujoco")]
    laws = [f"{law.__module__}.{law.__qualname__}" for law in kernel_sources.LAWS]
    digest = hashlib.sha256(" ".join([sys.version, platform.machine(), *versions]).encode())
    digest.update(" ".join(laws).encode())
    here = Path(__file__).parent
    sources = (*kernel_sources.source_files(), kernel_sources.__file__, __file__)
    compiling = ("compiled.py", "_kernel.py", "_entry_compile.py", "machine_code.py")
    compiling += ("callbacks.py",)
    for name in (*sources, *(here / name for name in compiling)):
        digest.update(Path(name).read_bytes())
    return digest.hexdigest()[:16]
