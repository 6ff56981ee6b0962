"""Command-line parsing shared by the applications: one error style (the scenario's value types
are the option schema's, :mod:`tt_mujoco.schema`).

Every CLI builds its parser from :class:`Parser`: a usage error is one line (no usage dump), exit
code 2, and a misspelt option or choice gets a "did you mean" hint, as the TOML keys, sweep
options and registries do (:func:`tt_mujoco.registry.closest`).
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from tt_mujoco.registry import closest
from tt_mujoco.schema_values import number_text

__all__ = [
    "BadInputError",
    "Parser",
    "StoreConstOnce",
    "StoreFalseOnce",
    "StoreOnce",
    "StoreTrueOnce",
    "given",
    "integer_at_least",
    "set_once",
]


class BadInputError(ValueError):
    """A user's mistake: reported as one line, exit code 2."""


def _ascii_integer(text: str) -> int:
    value = number_text(text, integer=True)
    if value is None:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer")
    return value


def _ascii_number(text: str) -> float:
    value = number_text(text)
    if value is None:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number")
    return value


def _path_text(text: str) -> Path:
    if not text.strip():
        raise argparse.ArgumentTypeError(f"{text!r} is not allowed: give a file or folder name")
    if any(ord(c) < 32 or ord(c) == 127 for c in text):  # a tab, a newline, an escape
        raise argparse.ArgumentTypeError(
            f"{text!r} is not allowed: a file or folder name holds no control characters"
        )
    return Path(text)


#: The readers of ``type=int``, ``type=float`` and ``type=Path`` options, which every
#: command's numbers and paths are read by: the option schema's numbers
#: (:func:`tt_mujoco.schema_values.number_text`: ASCII, a whole float as an integer), not
#: Python's ``int``, which reads ``"６４"`` as 64; a path that names something (an empty one
#: is the current folder to ``Path``).
_NUMBER_TYPES = {int: _ascii_integer, float: _ascii_number, Path: _path_text}

#: What a value that starts with "-" is when it is a number (argparse takes only "-5" and
#: "-.5" for one, and "-1e3" or "-inf" for an option it does not know): then a value.
_NEGATIVE_NUMBER = re.compile(
    r"^-(\d+\.?\d*([eE][-+]?\d+)?|\.\d+([eE][-+]?\d+)?|inf|infinity|nan)$", re.IGNORECASE
)


#: Where a namespace keeps, per option, the flag that set it and the value (the parser's own
#: bookkeeping: no option is named so).
_GIVEN = "_given_by"


def given(namespace) -> dict[str, str]:
    """The options the command line gave (dest -> the flag and value as given), as
    :func:`set_once` kept them: what a command refuses where another option makes it idle."""
    return {dest: flag for dest, (flag, _) in namespace.__dict__.get(_GIVEN, {}).items()}


def _said(value) -> str:
    return repr(str(value)) if isinstance(value, Path) else repr(value)


def set_once(parser, namespace, dest: str, flag: str, value) -> None:
    """Set the option ``dest`` from ``flag``: one command line that sets an option twice to
    different values (``--no-disturbance --disturbance-mode wrench``, ``--video --no-video``,
    ``--duration 1 --duration 2``) is refused, naming both, rather than the last one winning
    in silence."""
    kept = namespace.__dict__.setdefault(_GIVEN, {})
    if dest in kept and kept[dest][1] != value:
        first, before = kept[dest]
        parser.error(
            f"{first} and {flag} both set {dest} ({_said(before)} and {_said(value)}), which "
            "cannot be both: give one of them"
        )
    kept[dest] = (flag, value)
    setattr(namespace, dest, value)


class StoreOnce(argparse.Action):
    """``--x VALUE``, given once or with the same value again (:func:`set_once`)."""

    def __call__(self, parser, namespace, values, option_string=None):
        set_once(parser, namespace, self.dest, f"{option_string} {values}", values)


class StoreConstOnce(argparse.Action):
    """A flag that sets one value (``--no-disturbance``; :func:`set_once`)."""

    def __init__(self, option_strings, dest, const=None, **kwargs):
        super().__init__(option_strings, dest, nargs=0, const=const, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):
        set_once(parser, namespace, self.dest, option_string, self.const)


class StoreTrueOnce(StoreConstOnce):
    """``action="store_true"``, given once or again (:func:`set_once`)."""

    def __init__(self, option_strings, dest, default=False, required=False, help=None):
        super().__init__(option_strings, dest, True, default=default, required=required, help=help)


class StoreFalseOnce(StoreConstOnce):
    """``action="store_false"``, given once or again (:func:`set_once`)."""

    def __init__(self, option_strings, dest, default=True, required=False, help=None):
        super().__init__(option_strings, dest, False, default=default, required=required, help=help)


#: argparse's storing actions, each as one that refuses a second, different value.
_ONCE_ACTIONS = {
    None: StoreOnce,
    "store": StoreOnce,
    "store_const": StoreConstOnce,
    "store_true": StoreTrueOnce,
    "store_false": StoreFalseOnce,
}


class Parser(argparse.ArgumentParser):
    """argparse with errors raised as :class:`BadInputError`, with a hint for misspellings,
    and numbers read as the option schema reads them (:data:`_NUMBER_TYPES`)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        for kind, reader in _NUMBER_TYPES.items():  # argparse's own registry of types
            self.register("type", kind, reader)
        # every option of every command: given twice, with two values, is refused
        for name, action in _ONCE_ACTIONS.items():
            self.register("action", name, action)
        self._negative_number_matcher = _NEGATIVE_NUMBER  # argparse reads it (3.11 to 3.13)

    def error(self, message: str):
        raise BadInputError(message + self._hint(message))

    def _hint(self, message: str) -> str:
        unknown = re.match(r"unrecognized arguments: (.*)", message)
        if unknown:
            options = [o for a in self._actions for o in a.option_strings if o.startswith("--")]
            for word in unknown.group(1).split():
                if word.startswith("--"):
                    close = closest(word.split("=")[0], options)
                    if close:
                        return f"; did you mean {close}?"
            return ""
        choice = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if choice:
            close = closest(choice.group(1), re.findall(r"'([^']*)'", choice.group(2)))
            if close:
                return f"; did you mean {close!r}?"
        return ""


def integer_at_least(name: str, low: int):
    """An argparse type: an integer >= ``low``, the message naming ``name``."""

    def parse(text: str) -> int:
        value = number_text(text, integer=True)
        if value is None or value < low:
            raise argparse.ArgumentTypeError(f"{name} {text!r} is not an integer >= {low}")
        return value

    return parse
