"""Packed stream words (sim/packed.py): the bytes equal the Python-int arithmetic they
replace, gaps sit right above the word, and bad input is refused."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.packed import as_bytes, as_ints, pack_fields, records

WIDTHS = st.lists(st.integers(1, 64), min_size=1, max_size=6).filter(lambda bs: sum(bs) <= 128)


@settings(max_examples=60, deadline=None)
@given(bits=WIDTHS, n=st.integers(0, 40), seed=st.integers(0, 2**32 - 1), gap_bits=st.sampled_from([8, 16]))
def test_packed_words_and_records_equal_the_int_arithmetic(bits, n, seed, gap_bits):
    rng = np.random.default_rng(seed)
    cols = [np.array([int.from_bytes(rng.bytes(8), "big") >> (64 - b) for _ in range(n)], dtype=np.uint64)
            for b in bits]
    for c, b in zip(cols, bits, strict=True):
        c[:1] = (1 << b) - 1     # every field's largest value once
    want = []
    for i in range(n):
        w = 0
        for c, b in zip(cols, bits, strict=True):
            w = (w << b) | int(c[i])
        want.append(w)
    total = sum(bits)
    packed = pack_fields(list(zip(cols, bits, strict=True)))
    assert packed.shape == (n, -(-total // 8)) and packed.dtype == np.uint8
    assert as_ints(packed) == want
    assert np.array_equal(as_bytes(want, total), packed)
    gaps = rng.integers(0, 1 << gap_bits, n)
    assert as_ints(records(packed, total, gaps, gap_bits)) == [(int(g) << total) | w for g, w in zip(gaps, want, strict=True)]


def test_a_wide_word_packs_like_its_int():
    # the SNU pixel bus's 70-bit write: end, z, rgb, addr (1280 x 1024: 21 address bits)
    z, rgb, addr = (1 << 24) - 1, 0x123456, (1 << 21) - 2
    row = pack_fields([(np.array([1]), 1), (np.array([z]), 24), (np.array([rgb]), 24), (np.array([addr]), 21)])
    assert as_ints(row) == [(1 << 69) | (z << 45) | (rgb << 21) | addr]
    assert as_ints(records(row, 70, [255], 8)) == [(255 << 70) | as_ints(row)[0]]


def test_bad_packing_input_is_refused():
    with pytest.raises(RasterhwError, match="does not fit 4 bits"):
        pack_fields([(np.array([16]), 4)])
    with pytest.raises(RasterhwError, match="128 bits"):
        pack_fields([(np.zeros(1), 64), (np.zeros(1), 64), (np.zeros(1), 1)])
    with pytest.raises(RasterhwError, match="gaps must lie in 0..255"):
        records(pack_fields([(np.array([1]), 8)]), 8, [256], 8)
    with pytest.raises(RasterhwError, match="does not fit 6 bits"):
        records(pack_fields([(np.array([64]), 7)]), 6, [0], 8)
    with pytest.raises(RasterhwError, match=r"\(N, 2\) uint8"):
        as_bytes(np.zeros((3, 1), np.uint8), 12)
