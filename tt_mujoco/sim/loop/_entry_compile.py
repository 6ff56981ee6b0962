"""Machine-code entries of the kernel's functions, compiled by numba (the background compile).

:func:`compile_entry` generates, for a function of the kernel and the arguments it was given
(the chunk loop and its records, the metrics' projection and its arrays), a function

.. code-block:: python

    def entry(ints, floats):
        return FUNCTION(ints[0], RECORD_0(RECORD_1(floats[0], ...), ARRAY_3(ints, 7)), ...)

which reads every leaf of the arguments from two flat arrays in the order
:func:`tt_mujoco.sim.loop.machine_code.flatten` writes them (an array rebuilt around its data
address, shape and strides; a C function around its address), then calls the kernel's function
(the chunk loop is ``_kernel.run_chunk``, :func:`~tt_mujoco.sim.loop.closed_loop.run_steps`
compiled), whose machine code numba links into the entry's. numba compiles it and hands over
its object code, which :mod:`~tt_mujoco.sim.loop.machine_code` stores and loads without numba.
"""

from __future__ import annotations

import numba
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic, typeof_impl
from numba.np.arrayobj import populate_array

from tt_mujoco.sim.loop import callbacks

__all__ = ["compile_entry"]

#: The entry's own signature.
ENTRY_SIGNATURE = (types.int64[::1], types.float64[::1])


def _word(context, builder, ints, at, j):
    """``ints[at + j]``, as machine code."""
    index = builder.add(at, context.get_constant(types.intp, j))
    return builder.load(builder.gep(ints.data, [index]))


def _array_maker(array_type):
    """An intrinsic ``make(ints, at)``: the array of ``array_type`` whose data address, shape
    and strides are ``ints[at:]`` (no owner: the caller holds the array while the loop runs)."""
    ndim = array_type.ndim

    @intrinsic
    def make(typingctx, ints_type, at_type):
        def codegen(context, builder, signature, args):
            ints = context.make_array(signature.args[0])(context, builder, args[0])
            word = lambda j: _word(context, builder, ints, args[1], j)  # noqa: E731
            data_type = context.get_data_type(array_type.dtype)
            array = context.make_array(array_type)(context, builder)
            populate_array(
                array,
                data=builder.inttoptr(word(0), data_type.as_pointer()),
                shape=[word(1 + i) for i in range(ndim)],
                strides=[word(1 + ndim + i) for i in range(ndim)],
                itemsize=context.get_constant(types.intp, context.get_abi_sizeof(data_type)),
                meminfo=None,
            )
            return array._getvalue()

        return array_type(ints_type, at_type), codegen

    return make


def _function_maker(function_type):
    """An intrinsic ``make(address)``: the first-class function of ``function_type`` at a C
    address (called as numba calls a ``cfunc``)."""

    @intrinsic
    def make(typingctx, address_type):
        def codegen(context, builder, signature, args):
            function = cgutils.create_struct_proxy(function_type)(context, builder)
            function.c_addr = builder.inttoptr(args[0], cgutils.voidptr_t)
            function.py_addr = cgutils.get_null_value(cgutils.voidptr_t)
            function.jit_addr = cgutils.get_null_value(cgutils.voidptr_t)
            return function._getvalue()

        return function_type(address_type), codegen

    return make


class _Source:
    """The entry's source, built leaf by leaf in :func:`~tt_mujoco.sim.loop.machine_code.
    flatten`'s order, and the names it reads."""

    def __init__(self):
        self.scope, self.ints, self.floats = {}, 0, 0

    def _name(self, prefix: str, value) -> str:
        name = f"{prefix}{len(self.scope)}"
        self.scope[name] = value
        return name

    def expression(self, value_type) -> str:
        """The expression that rebuilds a value of ``value_type``."""
        if isinstance(value_type, (types.NamedTuple, types.NamedUniTuple)):
            cls = self._name("RECORD_", value_type.instance_class)
            return f"{cls}({', '.join(self.expression(t) for t in value_type.types)})"
        if isinstance(value_type, types.BaseTuple):
            return "(" + "".join(f"{self.expression(t)}, " for t in value_type.types) + ")"
        if isinstance(value_type, types.Array):
            make = self._name("ARRAY_", _array_maker(value_type))
            self.ints += 1 + 2 * value_type.ndim
            return f"{make}(ints, {self.ints - 1 - 2 * value_type.ndim})"
        if isinstance(value_type, types.Float):
            self.floats += 1
            return f"floats[{self.floats - 1}]"
        if isinstance(value_type, types.FunctionType):
            make = self._name("FUNCTION_", _function_maker(value_type))
            self.ints += 1
            return f"{make}(ints[{self.ints - 1}])"
        if isinstance(value_type, (types.Boolean, types.Integer)):
            self.ints += 1
            test = " != 0" if isinstance(value_type, types.Boolean) else ""
            return f"(ints[{self.ints - 1}]{test})"
        raise TypeError(f"no entry reads a {value_type}")


def _typed(k_mod, value):
    """numba's type of a record value, its C functions typed by their kind as the kernel's
    placeholders are (a placeholder of the loop's own is a ``ctypes`` function to numba)."""
    if isinstance(value, tuple):
        items = [_Typed(_typed(k_mod, v)) for v in value]
        return numba.typeof(type(value)(*items) if hasattr(value, "_fields") else tuple(items))
    kind = callbacks.kind_of(value)
    if kind is not None:
        return numba.typeof(k_mod.no_user_law if kind == callbacks.LAW else k_mod.no_hook)
    return numba.typeof(value)


class _Typed:
    """A stand-in whose numba type is given (:func:`_typed` of a tuple)."""

    def __init__(self, numba_type):
        self.numba_type = numba_type


@typeof_impl.register(_Typed)
def _typeof_typed(value, context):
    return value.numba_type


def compile_entry(k_mod, name: str, args: tuple) -> tuple[bytes, dict]:
    """The entry of the kernel's function ``name`` for ``args`` compiled: its object code and
    what loading it needs (the CPython wrapper's and the environment's symbols, the number of
    ints and floats it reads)."""
    source = _Source()
    rebuilt = ", ".join(source.expression(_typed(k_mod, value)) for value in args)
    # the kernel's function called, not inlined here: the chunk loop's steps inlined into this
    # function left a path schedule's gains unlogged (tests/test_compiled.py)
    scope = {**source.scope, "FUNCTION": getattr(k_mod, name)}
    exec(f"def entry(ints, floats):\n    return FUNCTION({rebuilt})", scope)
    entry = njit(nogil=True)(scope["entry"])  # with the counting: a callee may allocate
    entry.compile(ENTRY_SIGNATURE)
    (compiled,) = entry.overloads.values()
    obj = compiled.library.serialize_using_object_code()[2][0]
    symbols = {
        "wrapper": compiled.fndesc.llvm_cpython_wrapper_name,
        "env": compiled.fndesc.env_name,
        "ints": source.ints,
        "floats": source.floats,
    }
    return obj, symbols
