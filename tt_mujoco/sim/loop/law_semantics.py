"""Where a compiled law cannot do what its Python form does, read from numba's typed code.

Two kinds of code are refused a compiled form (the Python loop runs the law, saying why and
where): integer arithmetic that can pass 2**63, and writes to what the law is given to read.

**Integers.** numba's integers are 64-bit: past 2**63 they wrap, where Python's grow. A
plain-number law whose integer arithmetic could multiply its way past 2**63 would give other
numbers on the compiled loop than on the Python loop: an integer product, power or left shift
(their in-place forms too) is refused. Counting and indexing stay compiled: ``j + 1``,
``hi - lo``, ``//``, ``%``, comparisons, ``int(x)``, ``range``: a sum passes 2**63 only from
integers beyond 2**62, which a law reaches by ``int`` of such a float, where the two forms
already differ (Python's ``int(1e30)`` is exact, numba's is not a number it can hold); an
index out of range raises in the compiled law as in Python, since it is bounds-checked
(:func:`tt_mujoco.sim.loop.compiled_law.compile_law`).

**Writes.** The Python form is given its measurement, reference, model, gains and vehicle as
named tuples and its path as a read-only array, so a write to them raises; numba's records and
arrays can be written, and the run's own values would change. Only the law's state is written.
What is read is the law's typed code and that of the helpers of its module that it calls.
"""

from __future__ import annotations

import linecache
import operator
import os

__all__ = ["WIDENING", "law_signature", "unreproducible_site"]

#: Integer operations whose result can pass 2**63 from operands far below it.
WIDENING = frozenset(
    (operator.mul, operator.imul, operator.pow, operator.ipow, operator.lshift, operator.ilshift)
)


def law_signature(dtypes: dict, sees_path: bool) -> tuple:
    """The numba types the law is called with by its C entry (the record views of its
    arguments, ``dt``, the torque limit, and, for a law that sees the path, the path table and
    the vehicle's record)."""
    from numba import from_dtype, types

    records = [
        from_dtype(dtypes[k]) for k in ("MEASUREMENT", "REFERENCE", "NOMINAL", "GAINS", "STATE")
    ]
    args = (*records, types.float64, types.float64)
    if sees_path:
        args += (types.Array(types.float64, 2, "C"), from_dtype(dtypes["VEHICLE"]))
    return args


def unreproducible_site(law, own_codes, state_type) -> str | None:
    """What ``law`` (a compiled numba dispatcher), or a helper it calls whose code is one of
    ``own_codes`` (the user's functions), does first that its Python form would not: ``"WHY,
    at FILE line N: CODE"``; None where there is nothing. ``state_type``: the numba type of the
    law's state record, the one record it may write."""
    from numba.core import ir, types

    seen: set = set()
    todo = [law]
    while todo:
        dispatcher = todo.pop()
        if id(dispatcher) in seen:
            continue
        seen.add(id(dispatcher))
        for result in dispatcher.overloads.values():
            typed = result.type_annotation
            kinds = typed.typemap
            given = _arguments(typed.blocks, ir)
            for block in typed.blocks.values():
                for stmt in block.body:
                    why = _unreproducible(stmt, kinds, state_type, given, ir, types)
                    if why:
                        return f"{why}, at {_place(stmt.loc)}"
                    if (
                        isinstance(stmt, ir.Assign)
                        and isinstance(stmt.value, ir.Expr)
                        and stmt.value.op == "call"
                    ):
                        todo += _own_helpers(kinds.get(stmt.value.func.name), own_codes)
    return None


def _arguments(blocks, ir) -> set:
    """The names a function's arguments are kept under (``m = arg(0)``, and copies of them)."""
    names: set = set()
    for block in blocks.values():
        for stmt in block.body:
            if isinstance(stmt, ir.Assign) and (
                isinstance(stmt.value, ir.Arg)
                or (isinstance(stmt.value, ir.Var) and stmt.value.name in names)
            ):
                names.add(stmt.target.name)
    return names


def _unreproducible(stmt, kinds, state_type, given, ir, types) -> str | None:
    if isinstance(stmt, ir.Assign) and isinstance(stmt.value, ir.Expr):
        expr = stmt.value
        if expr.op in ("binop", "inplace_binop") and _can_pass_int64(
            expr, kinds[stmt.target.name], kinds, types
        ):
            return (
                "its integer arithmetic can pass 2**63, where numba's integers wrap and "
                "Python's grow (compute with floats)"
            )
    elif isinstance(stmt, ir.SetAttr):
        kind = kinds[stmt.target.name]
        if isinstance(kind, types.Record) and kind != state_type:
            return (
                f"it writes {stmt.attr!r} of a record it is given to read, which its Python "
                "form cannot (only its state is written)"
            )
    elif isinstance(stmt, ir.SetItem | ir.StaticSetItem) and stmt.target.name in given:
        # the path is the one table a law is given (a helper may be handed a buffer of its own)
        if isinstance(kinds[stmt.target.name], types.Array) and kinds[stmt.target.name].ndim == 2:
            return (
                "it writes into the path it is given to read, which its Python form cannot "
                "(the table is read-only)"
            )
    return None


def _can_pass_int64(expr, result, kinds, types) -> bool:
    if not isinstance(result, types.Integer) or expr.fn not in WIDENING:
        return False
    return not all(isinstance(kinds[v.name], types.Literal) for v in (expr.lhs, expr.rhs))


def _own_helpers(function_type, own_codes) -> list:
    """The compiled helpers behind a call's function type (``register_jitable`` keeps them in
    its template's cache) whose code is the user's."""
    found = []
    for template in getattr(function_type, "templates", None) or ():
        for cached in getattr(template, "_impl_cache", {}).values():
            dispatcher = cached[0] if isinstance(cached, tuple) else cached
            py_func = getattr(dispatcher, "py_func", None)
            if py_func is not None and py_func.__code__ in own_codes:
                found.append(dispatcher)
    return found


def _place(loc) -> str:
    code = linecache.getline(loc.filename, loc.line).strip()
    return f"{os.path.basename(loc.filename)} line {loc.line}: {code}"
