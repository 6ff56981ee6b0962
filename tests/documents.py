"""Nested documents (JSON files, TOML tables) for the property-based tests of the readers:
values of any shape, every key path of a document, and what holds a path's last key."""

from __future__ import annotations

from hypothesis import strategies as st


def nested(scalars, *, max_size: int = 3, key_size: int = 6, max_leaves: int = 8):
    """``scalars``, and lists and tables of them, nested."""
    return st.recursive(
        scalars,
        lambda inner: (
            st.lists(inner, max_size=max_size)
            | st.dictionaries(st.text(max_size=key_size), inner, max_size=max_size)
        ),
        max_leaves=max_leaves,
    )


def key_paths(doc, prefix=(), depth: int | None = None):
    """Every key path of a nested document (lists by index), under ``prefix``; with ``depth``,
    none below that many keys of ``prefix``."""
    items = doc.items() if isinstance(doc, dict) else enumerate(doc)
    for key, value in items:
        yield (*prefix, key)
        if isinstance(value, dict | list) and (depth is None or len(prefix) < depth):
            yield from key_paths(value, (*prefix, key), depth)


def parent_of(doc, path):
    """The table or list of ``doc`` that holds ``path``'s last key."""
    for key in path[:-1]:
        doc = doc[key]
    return doc
