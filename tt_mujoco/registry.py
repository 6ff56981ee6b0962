"""Registries of named parts and the ``module:Name`` / ``path/to/file.py:Name`` hooks.

Controllers, paths, metrics and disturbances are each looked up by name in a :class:`Registry`.
A name that is not registered but has the form ``package.module:Name`` or
``path/to/file.py:Name`` is imported on first use, so a user adds a part without editing the
package: the same text works on the command line, in a TOML scenario, in a sweep (its worker
processes import the hook themselves) and from Python.

>>> from tt_mujoco.registry import Registry
>>> shapes = Registry("shape")
>>> @shapes.register("square")
... def square(side):
...     return side * side
>>> shapes.resolve("square")(3)
9
"""

from __future__ import annotations

import difflib
import hashlib
import importlib
import importlib.util
import math
import os
import sys
from collections.abc import Callable, Iterator
from numbers import Real
from pathlib import Path

from tt_mujoco.guard import keeping_process_state, one_line, shown_error, users_failure

__all__ = [
    "HookError",
    "Registry",
    "call_hook",
    "check_finite_fields",
    "closest",
    "describe_failure",
    "existing_file",
    "finite_number",
    "is_hook",
    "load_hook",
    "normalise_hook",
    "real_number",
    "shown",
]


def existing_file(path, what: str) -> Path:
    """``path`` as a Path if it is an existing file; else ValueError naming it and ``what`` it is
    for ("path file", "config file"), also for a name the file system refuses (too long)."""
    file = Path(path)
    try:
        is_file = file.is_file()
    except OSError as err:
        raise ValueError(f"{what} {shown(str(path))}: {err.strerror}") from None
    if not is_file:
        raise ValueError(f"{what} {str(path)!r} does not exist (or is not a file)")
    return file


def check_finite_fields(obj, what: str, names) -> None:
    """Refuse a field of ``obj`` among ``names`` that is not a finite number (a bool is not one),
    naming it as ``what name=value`` (the physical options' records check their fields so)."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValueError(f"{what} {name}={value!r} is not allowed: it must be a number")
        if not math.isfinite(value):
            raise ValueError(f"{what} {name}={value!r} is not allowed: it must be finite")


def shown(value, limit: int = 80) -> str:
    """``repr(value)`` for a message, on one line (:func:`~tt_mujoco.guard.one_line`) and cut
    to ``limit`` characters (a 10 MB value is not echoed back), NumPy's scalars as the plain
    numbers they hold (``-3``, not ``np.int64(-3)``), in a tuple or list too; a user's object
    whose ``repr`` fails is named by its type."""
    try:
        text = repr(_plain(value))
        if not isinstance(text, str):
            raise TypeError("__repr__ returned a non-string")
        text = one_line(text)
    except BaseException as err:
        if not users_failure(err):
            raise
        return f"<a {type(value).__name__} whose repr fails>"
    if len(text) <= limit:
        return text
    return f"{text[: limit - 30]}... ({len(text)} characters)"


def _plain(value, depth: int = 2):
    """``value`` with NumPy's scalars (told without importing NumPy) as Python's, in tuples
    and lists ``depth`` deep."""
    kind = type(value)
    if kind.__module__ == "numpy" and kind.__name__ != "ndarray" and hasattr(value, "item"):
        return value.item()
    if depth and kind in (tuple, list) and len(value) <= 64:
        return kind(_plain(item, depth - 1) for item in value)
    return value


def real_number(value) -> bool:
    """Whether ``value`` is a real number, finite or not (a NumPy scalar included; a bool,
    Python's or NumPy's, is not: NumPy's is no ``Real`` at all)."""
    return isinstance(value, Real) and not isinstance(value, bool)


def finite_number(value) -> float | None:
    """``value`` as a float if it is a finite real number (:func:`real_number`), else None:
    the one test of "a number" for what a user's code returns. A bool, a string, a complex,
    a NaN or an infinity, an integer beyond a float and any container are not."""
    if not real_number(value):
        return None
    try:
        number = float(value)
    except (OverflowError, TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def closest(word: str, choices) -> str | None:
    """The choice closest to a misspelt ``word`` (for "did you mean" hints), or None."""
    match = difflib.get_close_matches(word, list(choices), n=1)
    return match[0] if match else None


class HookError(ValueError):
    """A hook that cannot be loaded, or that fails before the run: the message names the hook
    and what was wrong."""


def users_file(filename: str) -> bool:
    """Whether ``filename`` is a user's own code: neither this package's nor a library's."""
    return not _inside_package(filename) and not _in_library(filename)


def _in_library(filename: str) -> bool:
    """Whether ``filename`` is Python's own library or an installed package's (NumPy's,
    SciPy's): a failure there is named at the user's line that called it too."""
    import sysconfig

    paths = sysconfig.get_paths()
    roots = {paths.get(key) for key in ("stdlib", "platstdlib", "purelib", "platlib")}
    return any(root and filename.startswith(root + os.sep) for root in roots)


def _inside_package(filename: str) -> bool:
    roots = [Path(__file__).resolve().parent]
    controllers = sys.modules.get("tt_mujoco.controllers")
    if controllers is not None and getattr(controllers, "__file__", None):
        roots.append(Path(controllers.__file__).resolve().parent)
    try:
        path = Path(filename).resolve()
    except (OSError, RuntimeError):
        return False
    return any(path.is_relative_to(root) for root in roots)


def describe_failure(err: BaseException) -> str:
    """What user code did wrong, in one line: ``file.py, line N: TypeError: message``, the
    place being the innermost frame of the traceback outside this package (the user's
    code); ``SystemExit`` is named as a call of ``sys.exit``."""
    import traceback

    frames = traceback.extract_tb(err.__traceback__)
    # no frame of the user's: the call itself failed (the arguments do not fit its signature),
    # or C code did; the package's own line would name the wrong file
    mine = [f for f in frames if not _inside_package(f.filename)]
    place = f"{mine[-1].filename}, line {mine[-1].lineno}: " if mine else ""
    own = [f for f in mine if users_file(f.filename)]
    if own and own[-1] is not mine[-1]:  # the user's line that called the library that failed
        place = f"{own[-1].filename}, line {own[-1].lineno} (in {mine[-1].filename}, line "
        place += f"{mine[-1].lineno}): "
    if isinstance(err, SyntaxError) and str(err.filename).endswith(".py"):
        # the compiler raised it for the file it read: that file's line, not the import's
        place = f"{err.filename}, line {err.lineno}: "
    if isinstance(err, SystemExit):
        return f"{place}it called sys.exit({shown(err.code)})"
    if isinstance(err, RecursionError):
        return f"{place}RecursionError: it recursed deeper than Python allows"
    text = shown_error(err)
    return f"{place}{type(err).__name__}{': ' + text if text else ''}"


def call_hook(what: str, fn, *args, **kwargs):
    """``fn(*args, **kwargs)``, a user's code called before the run; what it raises that is
    its failure (:func:`tt_mujoco.guard.users_failure`) becomes a :class:`HookError` naming
    ``what``, the file and the line."""
    try:
        with keeping_process_state():
            return fn(*args, **kwargs)
    except BaseException as err:
        if not users_failure(err):
            raise
        raise HookError(f"{what} failed: {describe_failure(err)}") from None


def is_hook(spec) -> bool:
    """Whether ``spec`` names a hook (``module:Name`` or ``file.py:Name``) rather than a name."""
    return isinstance(spec, str) and ":" in spec.strip()


def _split(spec: str, what: str) -> tuple[str, str]:
    where, _, name = spec.strip().rpartition(":")
    if not where or not name.isidentifier():
        raise HookError(
            f"{what} {spec!r} is not allowed: a hook is 'package.module:Name' or "
            "'path/to/file.py:Name'"
        )
    return where, name


def normalise_hook(spec: str, base_dir: Path | None = None) -> str:
    """The hook with a file path made absolute (relative to ``base_dir``, else the current
    folder), so that it means the same file from any working directory; module hooks and
    plain names are returned unchanged."""
    if not is_hook(spec):
        return spec
    where, name = spec.strip().rsplit(":", 1)
    if not where.endswith(".py"):
        return spec.strip()
    path = Path(where).expanduser()
    if not path.is_absolute():
        path = (base_dir or Path.cwd()) / path
    return f"{path.resolve()}:{name}"


def _module_from_file(path: Path, what: str, spec: str):
    try:
        resolved = path.expanduser().resolve(strict=True)
    except (OSError, RuntimeError):
        raise HookError(f"{what} {spec!r}: file {str(path)!r} not found") from None
    if not resolved.is_file():
        raise HookError(f"{what} {spec!r}: {str(path)!r} is not a file")
    digest = hashlib.sha1(str(resolved).encode()).hexdigest()[:12]
    module_name = f"tt_mujoco_user_{resolved.stem}_{digest}"
    if module_name in sys.modules:
        return sys.modules[module_name]
    loader_spec = importlib.util.spec_from_file_location(module_name, resolved)
    if loader_spec is None or loader_spec.loader is None:
        raise HookError(f"{what} {spec!r}: {str(path)!r} cannot be imported")
    module = importlib.util.module_from_spec(loader_spec)
    sys.modules[module_name] = module  # before exec: dataclasses and pickling look it up
    try:
        loader_spec.loader.exec_module(module)
    except BaseException as err:  # sys.exit at import must not end the run as done
        del sys.modules[module_name]
        if not users_failure(err):
            raise
        raise HookError(
            f"{what} {spec!r}: importing {str(path)!r} failed: {describe_failure(err)}"
        ) from None
    return module


def load_hook(spec: str, what: str = "hook") -> object:
    """Import the object a hook names.

    Parameters
    ----------
    spec : str
        ``package.module:Name`` or ``path/to/file.py:Name`` (relative to the current folder).
    what : str
        What the hook is for ("controller", "path", ...), for messages.

    Raises
    ------
    HookError
        The module or file cannot be imported or has no such name.
    """
    where, name = _split(spec, what)
    if where.endswith(".py"):
        module = _module_from_file(Path(where), what, spec)
    else:
        try:
            module = importlib.import_module(where)
        except ImportError as err:
            raise HookError(
                f"{what} {spec!r}: module {where!r} cannot be imported: {err}"
            ) from None
        except BaseException as err:
            if not users_failure(err):
                raise
            raise HookError(
                f"{what} {spec!r}: importing module {where!r} failed: {describe_failure(err)}"
            ) from None
    try:
        return getattr(module, name)
    except AttributeError:
        public = sorted(n for n in vars(module) if not n.startswith("_"))
        hint = closest(name, public)
        extra = f"; did you mean {hint!r}?" if hint else ""
        raise HookError(f"{what} {spec!r}: {where!r} has no {name!r}{extra}") from None


def _key(name: str) -> str:
    return name.strip().lower().replace("-", "_")


def _identity(obj) -> tuple[str, str]:
    """Where a part is defined: its module and qualified name."""
    return str(getattr(obj, "__module__", "")), str(getattr(obj, "__qualname__", repr(obj)))


def _shown(obj) -> str:
    module, name = _identity(obj)
    built_in = module.startswith("tt_mujoco")
    return f"{'the built-in ' if built_in else ''}{module}.{name}" if module else repr(obj)


class Registry:
    """Named parts of one kind, extensible by registration or by hook.

    Parameters
    ----------
    what : str
        The kind of part, for messages ("controller", "path", "metric", "disturbance").
    also : str
        Other accepted forms, for messages (e.g. "a path to a .csv file").
    called_as : tuple of str, optional
        The arguments a part of this kind is called with, by name, where it is a function
        (:meth:`check_call` refuses one whose signature cannot take them, before the run).
    """

    def __init__(self, what: str, also: str = "", called_as: tuple[str, ...] | None = None):
        self.what = what
        self.also = also
        self.called_as = called_as
        self._items: dict[str, object] = {}

    def check_call(self, obj, spec) -> None:
        """Refuse ``obj``, the part ``spec`` stands for, when it is not callable or its
        signature cannot take :attr:`called_as` (a metric ``m(timeseries, path)``, a
        disturbance ``d(t)``): a ``ValueError`` before the run, where the call would fail after
        it. A callable without a signature Python can read (one written in C) is taken as it
        is."""
        import inspect

        if not callable(obj):
            raise ValueError(
                f"{self.what} {shown(spec)} is not allowed: {shown(obj)} is not callable"
            )
        if self.called_as is None:
            return
        try:
            signature = inspect.signature(obj)
        except (TypeError, ValueError):
            return
        try:
            signature.bind(*self.called_as)
        except TypeError as err:
            raise ValueError(
                f"{self.what} {shown(spec)} is not allowed: it is called as "
                f"{self.what}({', '.join(self.called_as)}), which its signature {signature} "
                f"does not take ({err})"
            ) from None

    def register(
        self, name: str, obj: object | None = None, *, replace: bool = False
    ) -> Callable | object:
        """Register ``obj`` under ``name`` (case and ``-``/``_`` are not significant); used
        without ``obj`` it is a decorator.

        A name is one part: a name taken by a built-in part, or by another part of the user's,
        is refused (``ValueError``) unless ``replace=True`` says so on purpose. The same part
        registered again (a module imported twice, a notebook cell run again: the same module
        and qualified name) replaces itself.
        """
        if not isinstance(name, str) or not name.strip() or ":" in name:
            raise ValueError(f"{self.what} name {name!r} is not allowed: use a plain word")

        def add(item):
            key = _key(name)
            old = self._items.get(key)
            if old is not None and old is not item and not replace:
                again = _identity(old) == _identity(item) and not _identity(old)[0].startswith(
                    "tt_mujoco"
                )
                if not again:
                    raise ValueError(
                        f"{self.what} name {name!r} is taken by {_shown(old)}: a name is one "
                        f"part; choose another name, or pass replace=True to replace it on "
                        "purpose"
                    )
            self._items[key] = item
            return item

        return add if obj is None else add(obj)

    def names(self) -> tuple[str, ...]:
        return tuple(self._items)

    def __contains__(self, name) -> bool:
        return isinstance(name, str) and _key(name) in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __getitem__(self, name: str):
        return self._items[_key(name)]

    def resolve(self, spec) -> object:
        """The registered part named ``spec``, or the object a hook names.

        Raises
        ------
        ValueError
            An unknown name (with the allowed names and a "did you mean" hint), or a hook
            that cannot be loaded (:class:`HookError`).
        """
        if isinstance(spec, str) and _key(spec) in self._items:
            return self._items[_key(spec)]
        if is_hook(spec):
            return load_hook(spec, self.what)
        raise self.unknown(spec)

    def unknown(self, spec) -> ValueError:
        """The error for a name that is neither registered nor a hook: the allowed names, the
        other accepted forms and the closest name."""
        allowed = ", ".join(repr(k) for k in self._items)
        hint = ""
        if isinstance(spec, str):
            close = closest(_key(spec), self._items)
            hint = f"; did you mean {close!r}?" if close else ""
        hook = "a hook 'package.module:Name' or 'path/to/file.py:Name'"
        if allowed:
            use = f"use one of {allowed}, {self.also + ', ' if self.also else ''}or {hook}"
        else:
            use = (
                f"no {self.what} is registered: use {self.also + ' or ' if self.also else ''}{hook}"
            )
        return ValueError(f"{self.what} name={shown(spec)} is not allowed: {use}{hint}")
