"""The ZB/M cocotb benches' stimulus and dump files (``tests/zbm_cocotb/``): words with idle
gaps in ``$readmemh`` hex files, the unit benches' index file, 128-bit frame dumps read back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.zbm import formats as F
from rasterhw.sim.engines.memh import memh_uint64, read_memh
from rasterhw.sim.zbm.testbench import random_gaps

__all__ = ["GAP_BITS", "memory_depth", "read_hex_words", "stimulus_depth", "write_hex",
           "write_unit_stimulus"]

GAP_BITS = 8             # idle clocks before a stimulus word, in the bench's stimulus files


def write_hex(path: Path, words, gaps, pw: int) -> None:
    """``words`` with ``gaps`` idle clocks each (above ``pw`` payload bits) as a hex file."""
    if len(words) and int(np.max(gaps, initial=0)) >= (1 << GAP_BITS):
        raise RasterhwError(f"gap {int(np.max(gaps))} does not fit the bench's {GAP_BITS}-bit gap field")
    text = "\n".join(f"{(int(g) << pw) | int(w):x}" for w, g in zip(words, gaps, strict=True))
    path.write_text((text or "0") + "\n")   # $readmemh wants at least one word


def read_hex_words(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """A $writememh dump of 128-bit words -> (s0, s1) uint64 arrays (low, high 64 bits)."""
    b = read_memh(path)
    if b.shape[1] > 16:
        raise RasterhwError(f"{path}: words wider than 128 bits")
    b = np.concatenate([np.zeros((b.shape[0], 16 - b.shape[1]), np.uint8), b], axis=1)
    return memh_uint64(b, 8, 16), memh_uint64(b, 0, 8)


def memory_depth(n: int) -> int:
    """A bench memory for ``n`` words: the smallest power of two (>= 1024) above ``n + 1``."""
    return max(1024, 1 << int(n + 2).bit_length())


def stimulus_depth(words: int, depth: int | None = None) -> int:
    """A bench's stimulus memory depth for ``words`` words: ``depth`` if given (it must hold them),
    else the smallest power of two (>= 1024) that does."""
    need = memory_depth(words)
    if depth is None:
        return need
    if not isinstance(depth, int) or depth < words + 2:
        raise RasterhwError(f"stimulus depth {depth!r} does not hold {words} words")
    return depth


def write_unit_stimulus(run_dir: Path, words: list[list[int]], gap_seed: int | None) -> tuple[list[int], list[int]]:
    """The cocotb unit bench's stimulus files (tb_zbm_unit.v): every unit's
    loader words in one ``stim.hex`` (with random idle gaps from ``gap_seed``, None: none) and
    ``index.hex``, two lines per unit (first word, number of words). Returns (words, index)."""
    flat, index = [], []
    for w in words:
        index += [len(flat), len(w)]
        flat += w
    write_hex(run_dir / "stim.hex", flat, random_gaps(len(flat), gap_seed), F.EP_WORD_BITS)
    (run_dir / "index.hex").write_text("\n".join(f"{v:x}" for v in index) + "\n")
    return flat, index
