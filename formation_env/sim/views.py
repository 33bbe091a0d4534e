"""Compiled views of the step's named tuples: the same fields behind one reference count.

A numba named tuple of arrays is a value: binding it to a variable (a stage's parameter, inlined or not)
increments the reference count of every array in it, and the matching decrements come where the variable dies.
numba's reference-count pruning removes such pairs only where nothing else is released in between, which a stage
with a loop, a temporary array or a call never satisfies; so each stage taking ``p`` (``StepParams``, ~70 arrays),
``s`` (``SimState``, ~40) and the decision's scratch (~35) took and released a count of each of them, every physics
step. A :class:`StructView` holds the same fields in a numba structref: binding it
costs one count, and ``view.field`` reads the field itself (an array's count taken and released in the same
statement, which the pruning removes). Stages read fields exactly as on the named tuple, so they compile for
either; the numbers are the same.

Views exist only inside compiled code (:func:`struct_view`); nothing here is boxed to Python.
"""

from __future__ import annotations

from numba.core import types as nbt
from numba.experimental import structref
from numba.extending import overload

__all__ = ["StructView", "view_type", "struct_view"]


@structref.register
class StructView(nbt.StructRef):
    """numba type of the view of a named tuple: its fields, names and types, in one structref."""

    def preprocess_fields(self, fields):
        return tuple((name, nbt.unliteral(typ)) for name, typ in fields)


def view_type(t: nbt.BaseNamedTuple) -> StructView:
    """The :class:`StructView` type of the numba named-tuple type ``t`` (its named-tuple fields views in turn)."""
    return StructView([(name, view_type(typ) if isinstance(typ, nbt.BaseNamedTuple) else typ)
                       for name, typ in zip(t.fields, t.types)])


def struct_view(t):
    """A :class:`StructView` of the named tuple ``t`` (compiled code only): its fields shared, not copied; a field
    that is a named tuple itself becomes a view too."""
    raise NotImplementedError("struct_view is compiled code only")


@overload(struct_view)
def _struct_view_overload(t):
    if not isinstance(t, nbt.BaseNamedTuple):
        return None
    typ = view_type(t)
    # one assignment per field: the field names are the named tuple's, known only here
    src = "def impl(t):\n    r = structref.new(typ)\n" + "".join(
        f"    r.{name} = struct_view(t.{name})\n" if isinstance(ft, nbt.BaseNamedTuple) else f"    r.{name} = t.{name}\n"
        for name, ft in zip(t.fields, t.types)) + "    return r\n"
    scope = {"structref": structref, "typ": typ, "struct_view": struct_view}
    exec(src, scope)  # noqa: S102 - generated from the named tuple's own field names
    return scope["impl"]
