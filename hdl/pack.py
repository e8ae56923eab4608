"""Pack a value into the bits of an Amaranth data layout, in plain Python.

``pack(layout, value)`` equals ``layout.const(value).as_bits()`` (tested) at a fraction of the
cost: benches that write thousands of stimulus words (the sparse broadcast records, EXPERTS
segments) use it instead of building an Amaranth constant per word. Struct layouts take
mappings (missing fields are 0), array layouts take sequences, plain shapes take integers
(wrapped to their width, as a constant of a signed shape is).
"""

from __future__ import annotations

from functools import cache

from amaranth.hdl import Shape
from amaranth.lib import data

__all__ = ["pack"]


#: plans by ``id(layout)``, with the layout kept alive beside its plan so the id is not reused.
#: Looked up by identity: hashing a layout is cheap, but a hash hit then compares the layouts with
#: ``==``, which for a data layout compares every field's shape (~150 us for the 14-field EXPERTS
#: segment, 20x the packing itself)
_plans: dict[int, tuple] = {}


def _plan(layout) -> tuple:
    """Flatten ``layout`` to ``((path, offset, width), ...)`` once per layout object."""
    hit = _plans.get(id(layout))
    if hit is not None and hit[0] is layout:
        return hit[1]
    plan = _flatten(layout)
    _plans[id(layout)] = (layout, plan)
    return plan


#: packers of struct layouts of plain fields, by plan (:func:`_flat_packer`)
_flat: dict[tuple, object] = {}


def _flat_packer(plan: tuple):
    """``get -> word`` for a plan of plain named fields: one expression
    ``(int(get(name, 0)) & mask) << offset | ...`` (a loop over the plan took 3x as long for the
    EXPERTS span PXP's 17-field DMM/P words, ~56,000 of them a ``sim pxp`` frame)."""
    terms = [f"((int(get({path[0]!r}, 0)) & {(1 << width) - 1}) << {off})" for path, off, width in plan]
    return eval("lambda get: " + (" | ".join(terms) or "0"))  # noqa: S307 - field names are repr()'d


@cache
def _flatten(layout) -> tuple:
    """Flatten ``layout`` to ``((path, offset, width), ...)`` (equal layouts share one plan)."""
    out = []

    def walk(shape, path, off):
        if isinstance(shape, data.StructLayout):
            for name, f in shape:
                walk(f.shape, (*path, name), off + f.offset)
        elif isinstance(shape, data.ArrayLayout):
            w = Shape.cast(shape.elem_shape).width
            for k in range(shape.length):
                walk(shape.elem_shape, (*path, k), off + k * w)
        else:
            out.append((path, off, Shape.cast(shape).width))

    walk(layout, (), 0)
    return tuple(out)


def pack(layout, value) -> int:
    """The bits of ``value`` in ``layout`` as an unsigned integer."""
    plan = _plan(layout)
    if type(value) is dict and plan in _flat:   # a flat struct from a dict: one expression
        return _flat[plan](value.get)
    if type(value) is dict and all(len(path) == 1 and isinstance(path[0], str) for path, _, _ in plan):
        _flat[plan] = _flat_packer(plan)
        return pack(layout, value)
    word = 0
    for path, off, width in plan:
        v = value
        for key in path:
            try:
                v = v[key]
            except KeyError:
                v = 0
                break
        word |= (int(v) & ((1 << width) - 1)) << off
    return word
