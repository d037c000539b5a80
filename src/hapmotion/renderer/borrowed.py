"""Array views that the compiled frame loop passes around without counting references to their memory.

numba counts the references to an array's memory with an atomic add and subtract wherever an array (or a view of
one) is bound to a name; the renderer's frame loop inlines a dozen steps a frame, each binding the arrays it is
given, about 70 atomic operations a frame and a third of the loop's time. A view :func:`borrowed` makes has no
memory owner (as an array numba makes from a raw pointer), so numba skips its counting. The view must not outlive
its owner: the loop borrows its arguments (the caller holds them for the whole call) and its own scratch arrays,
which :func:`keep_alive` keeps until the loop has ended.
"""

from __future__ import annotations

from numba.core import cgutils, types
from numba.extending import intrinsic, overload


def borrowed(arr):
    """A view of array ``arr`` (same type, shape, strides and memory) without a memory owner: numba counts no
    references to it. Valid while ``arr``'s memory is (see the module docstring). In Python (``NUMBA_DISABLE_JIT``)
    the array itself."""
    return arr


def keep_alive(owners) -> None:
    """Nothing, at this point of the function: a use of ``owners`` that keeps them (and the memory of the views
    :func:`borrowed` made of them) alive until here."""


@intrinsic
def _ownerless_view(typingctx, arr):
    def codegen(context, builder, sig, args):
        src = context.make_array(sig.args[0])(context, builder, value=args[0])
        view = context.make_array(sig.return_type)(context, builder)
        for name in ("nitems", "itemsize", "data", "shape", "strides"):
            setattr(view, name, getattr(src, name))
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        view.parent = cgutils.get_null_value(view.parent.type)
        return view._getvalue()

    return arr(arr), codegen


@intrinsic
def _use(typingctx, owners):
    def codegen(context, builder, sig, args):
        return context.get_dummy_value()

    return types.none(owners), codegen


@overload(borrowed)
def _borrowed_compiled(arr):
    if isinstance(arr, types.Array):
        return lambda arr: _ownerless_view(arr)
    return None


@overload(keep_alive)
def _keep_alive_compiled(owners):
    return lambda owners: _use(owners)
