"""Command-line parsing shared by the applications: one error style (the scenario's value types
are the option schema's, :mod:`tt_mujoco.schema`).

Every CLI builds its parser from :class:`Parser`: a usage error is one line (no usage dump), exit
code 2, and a misspelt option or choice gets a "did you mean" hint, as the TOML keys, sweep
options and registries do (:func:`tt_mujoco.registry.closest`).
"""

from __future__ import annotations

import argparse
import re

from tt_mujoco.registry import closest

__all__ = ["BadInputError", "Parser", "integer_at_least"]


class BadInputError(ValueError):
    """A user's mistake: reported as one line, exit code 2."""


class Parser(argparse.ArgumentParser):
    """argparse with errors raised as :class:`BadInputError`, with a hint for misspellings."""

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
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{name} {text!r} is not an integer >= {low}"
            ) from None
        if value < low:
            raise argparse.ArgumentTypeError(f"{name} {text!r} is not an integer >= {low}")
        return value

    return parse
