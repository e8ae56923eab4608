"""``sim.memh``: $writememh dumps decoded in one pass equal a word-by-word ``int(word, 16)``."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.memh import memh_uint64, read_memh


def _words(b: np.ndarray) -> list[int]:
    return [int.from_bytes(row.tobytes(), "big") for row in b]


@pytest.mark.parametrize("digits", [1, 6, 12, 13, 32])
def test_fixed_width_dump_equals_int_parse(tmp_path, digits):
    rng = np.random.default_rng(digits)
    vals = [int("".join("0123456789abcdef"[d] for d in rng.integers(0, 16, digits)), 16) for _ in range(500)]
    f = tmp_path / "m.hex"
    f.write_text("".join(f"{v:0{digits}x}\n" for v in vals))
    assert _words(read_memh(f, len(vals))) == vals


def test_comments_addresses_and_short_words(tmp_path):
    f = tmp_path / "m.hex"
    f.write_text("// dump\n@0\n1F\nabc\n\n7\n")
    b = read_memh(f)
    assert _words(b) == [0x1F, 0xABC, 7]
    assert memh_uint64(b, 0, 2).tolist() == [0x1F, 0xABC, 7]


def test_x_digits_and_wrong_count_are_one_line_errors(tmp_path):
    f = tmp_path / "m.hex"
    f.write_text("00x\n001\n")
    with pytest.raises(RasterhwError, match="X or Z"):
        read_memh(f)
    f.write_text("000\n001\n")
    with pytest.raises(RasterhwError, match="2 words, expected 3"):
        read_memh(f, 3)


def test_uint64_slices():
    b = np.array([[0x01, 0x02, 0x03, 0x04, 0x05, 0x06]], np.uint8)
    assert memh_uint64(b, 0, 3).tolist() == [0x010203]
    assert memh_uint64(b, 3, 6).tolist() == [0x040506]
    with pytest.raises(ValueError):
        memh_uint64(b, 0, 0)
