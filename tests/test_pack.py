"""hdl/pack.py: the plain-Python packer equals Amaranth's constant of the layout."""

from __future__ import annotations

import numpy as np
from amaranth.hdl import signed, unsigned
from amaranth.lib import data
from rasterhw.hdl.experts.pxp import seg_layout
from rasterhw.hdl.pack import pack
from rasterhw.hdl.sparse.layouts import BROADCAST, HEADER, WINDOW


def _random_value(layout, rng):
    if isinstance(layout, data.StructLayout):
        return {name: _random_value(f.shape, rng) for name, f in layout}
    if isinstance(layout, data.ArrayLayout):
        return [_random_value(layout.elem_shape, rng) for _ in range(layout.length)]
    s = layout
    lo, hi = (-(1 << (s.width - 1)), 1 << (s.width - 1)) if s.signed else (0, 1 << s.width)
    return int(rng.integers(lo, hi)) if s.width < 63 else int.from_bytes(rng.bytes(8)) % (hi - lo) + lo


def test_pack_equals_amaranth_const_on_every_bench_layout():
    rng = np.random.default_rng(3)
    for lay in (BROADCAST, HEADER, WINDOW, seg_layout()):
        for _ in range(50):
            v = _random_value(lay, rng)
            assert pack(lay, v) == lay.const(v).as_bits(), lay


def test_pack_missing_fields_are_zero_and_negative_values_wrap():
    lay = data.StructLayout({"a": signed(4), "b": unsigned(3), "c": data.ArrayLayout(signed(2), 2)})
    assert pack(lay, {"b": 5}) == 5 << 4
    assert pack(lay, {"a": -1, "c": [-1, 1]}) == 0xF | (0b0111 << 7)
    assert pack(lay, {"a": -1, "c": [-1, 1]}) == lay.const({"a": -1, "c": [-1, 1]}).as_bits()


def test_pack_of_a_flat_struct_from_a_partial_dict_fills_zeros():
    """The flat-struct path (one ``dict.get`` a field): missing fields are 0, as in the general walk
    (a dict subclass takes the general walk) and in Amaranth's constant."""
    from rasterhw.hdl.experts.pxp_span import dmm_layout
    lay = dmm_layout()
    rng = np.random.default_rng(5)
    for _ in range(20):
        full = _random_value(lay, rng)
        part = {k: v for k, v in full.items() if rng.random() < 0.5}
        want = lay.const(part).as_bits()
        assert pack(lay, part) == want
        assert pack(lay, type("D", (dict,), {})(part)) == want
