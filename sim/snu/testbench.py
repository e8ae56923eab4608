# amaranth: UnusedElaboratable=no
"""Testbenches of the SNU blocks (``sim/testbench.py``): pixel writes in, the frame memory out.

Both blocks keep what they make in their frame memory; the engines' read-out adapter
(``sim/engines/readout.py: ReadOut``) ends every write stream with a token and then streams the memory out
(``o``: ``{rgb, z}`` per word, address order, draw buffer), so the generic engines compare it with
the golden frame (``golden_model/snu/pixelbus.py: pixelbus_frame``) word for word.
"""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.snu import pixelbus as golden
from rasterhw.golden_model.snu.formats import RGB_BITS
from rasterhw.golden_model.snu.pixelstream import PixelStream
from rasterhw.golden_model.snu.words import payload_fields
from rasterhw.sim.engines.verilog_cache import factory_params
from rasterhw.sim.packed import pack_fields
from rasterhw.sim.snu.frame_format import GAP_BITS, SCHEDULE
from rasterhw.sim.testbench import Expected, Run, Stimulus, Testbench

__all__ = ["BankBench", "BusBench", "FrameBench", "frame_of"]


def _addr_bits(n: int) -> int:
    return max(1, (n - 1).bit_length())     # the blocks' max(1, ceil_log2(n))


def _port_words(stream: PixelStream, idx: np.ndarray, aw: int, gaps) -> tuple[np.ndarray, np.ndarray | None]:
    """The writes ``idx`` as port words, then the end token (the payload's top bit + 1), packed
    (``sim/packed.py``: one row of bytes per word, no Python int per write)."""
    fields = payload_fields(stream, idx, aw)
    words = _then_end(pack_fields([(np.zeros(idx.size, np.int64), 1)] + fields), 1 + sum(b for _, b in fields))
    return words, (None if gaps is None else np.append(np.asarray(gaps, dtype=np.int64)[idx], 0))


def _then_end(words: np.ndarray, bits: int) -> np.ndarray:
    """Packed ``words`` of ``bits`` bits, then the end token: the top bit alone."""
    end = np.zeros((1, words.shape[1]), np.uint8)
    pad = 8 * words.shape[1] - bits          # unused bits above the word in its first byte
    end[0, pad // 8] = 1 << (7 - pad % 8)
    return np.concatenate([words, end])


def _stream(rng: np.random.Generator, width: int, height: int, n: int, pipes: int, z_bits: int,
            n_banks: int) -> tuple[PixelStream, str]:
    """A random stream: uniform, scan-line runs, column runs or one bank; full or narrow Z (ties)."""
    npix = width * height
    kind = str(rng.choice(["uniform", "scanline", "vertical", "one-bank"]))
    if kind == "uniform":
        addr = rng.integers(0, npix, n)
    elif kind in ("scanline", "vertical"):
        run = int(rng.integers(3, 20))
        step = 1 if kind == "scanline" else width
        addr = (rng.integers(0, npix, -(-n // run))[:, None] + step * np.arange(run)).ravel()[:n] % npix
    else:
        bank = int(rng.integers(0, n_banks))
        addr = np.minimum(rng.integers(0, -(-npix // n_banks), n) * n_banks + bank, npix - 1)
    narrow = bool(rng.random() < 0.5)
    z = rng.integers(0, 16, n) if narrow else rng.integers(0, 1 << z_bits, n)
    pipe = rng.integers(0, pipes, n)
    s = PixelStream(width, height, addr, rng.integers(0, 1 << RGB_BITS, n), z, pipe, z_bits=z_bits)
    return s, f"{n} {kind} writes, {'narrow' if narrow else 'full'} Z, {pipes} pipeline(s)"


def frame_of(run: Run, z_bits: int, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """The read-out words of ``run`` as ``(rgb, z)`` arrays of ``shape`` (int64)."""
    w = np.array(run.words["o"], dtype=np.int64)
    return (w >> z_bits).reshape(shape), (w & ((1 << z_bits) - 1)).reshape(shape)


def _read_out(block, ports: tuple[str, ...], words: int):
    """The frame-memory block behind the engines' read-out adapter (``ReadOut``): an end token on
    every write stream, then the draw buffer (``rd_buf`` 0) streamed out as ``{rgb, z}`` (``z``
    low); ``i_cmd`` idle (no clear, no swap: the memory starts at zero, as after a clear)."""
    # imported here, as Amaranth: a run whose Verilog is cached constructs no block
    from amaranth import Cat
    from rasterhw.sim.engines.readout import ReadOut

    def address(m, b, addr):
        m.d.comb += b.rd_addr.eq(addr)

    return ReadOut(block, ports=ports, words=words, address=address, data=lambda b: Cat(b.rd_z, b.rd_rgb),
                   fixed={"i_cmd.valid": 0, "rd_buf": 0})


def _frame_words(rgb: np.ndarray, z: np.ndarray, z_bits: int) -> list[int]:
    return ((rgb.ravel() << z_bits) | z.ravel()).tolist()


class BankBench(Testbench):
    """``pixelbus-bank``: pixel writes (bank-local address, RGB, Z) in on ``i`` back to back, the
    bank's draw buffer and Z out (``o``, ``depth`` words). Golden: the writes applied in order with
    the strict Z test (``pixelbus_frame``), and the cycle count of one bank (:func:`bank_cycles`:
    one write per memory cycle, the block's documented throughput; the read-out once the last
    memory cycle ended). The bus's golden cycle model (two pipelines' slots) is not one bank's."""

    block = "pixelbus-bank"

    def dut(self, params: dict):
        return _read_out(super().dut(params), self.inputs, params["depth"])

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        s, what = _stream(rng, params["depth"], 1, int(rng.integers(40, 200)), 1, params["z_bits"], 1)
        return self.stimulus_of(params, s, what=f"{what}, seed {seed}")

    def stimulus_of(self, params: dict, stream: PixelStream, gaps=None, what: str = "") -> Stimulus:
        """``stream`` (one pipeline, ``addr`` bank-local, a ``depth`` x 1 frame) as the bank's words."""
        words, g = _port_words(stream, np.arange(len(stream)), _addr_bits(params["depth"]), gaps)
        return Stimulus({"i": words}, {} if g is None else {"i": g}, what=what, source=stream)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        s = stim.source
        rgb, z = golden.pixelbus_frame(s, accept=np.arange(len(s)))
        return Expected({"o": _frame_words(rgb, z, params["z_bits"])}, cycles=bank_cycles(params, stim))


def bank_cycles(params: dict, stim: Stimulus) -> int:
    """The edges of a bank run with ``o`` always ready (``ReadOut``'s timing): write ``k`` is
    offered ``gap`` clocks after the edge following write ``k - 1``'s accept and accepted once the
    bank is free, ``mem_cycle`` clocks after that accept (``PixelBusBank``: "one write per
    ``mem_cycle`` clocks"); the end token is taken when offered; the sweep starts at the first
    clock with the token seen and the last memory cycle over, and gives word ``j`` at the edge
    after it plus ``j``: the cycles are that start + ``depth`` + 1 (added for mutation coverage,
    docs/mutation.md: the bank's memory-cycle counter was unchecked)."""
    m, g = params["mem_cycle"], stim.gaps_of("i")
    n = len(stim.words["i"]) - 1           # the writes; the last word is the end token
    if n == 0:
        return int(g[0]) + 1 + params["depth"] + 1
    accept = int(g[0]) + int(np.maximum(m, 1 + g[1:n]).sum())
    start = max(accept + 1 + int(g[n]) + 1, accept + m)
    return start + params["depth"] + 1


class BusBench(Testbench):
    """``pixelbus``: the two pipelines' pixel writes (linear address, RGB, Z) in on ``i_pipe0`` and
    ``i_pipe1``, the draw buffer and Z of the whole frame out (``o``, ``width * height`` words).
    Golden: ``pixelbus_accept_cycles`` (every write's slot) and ``pixelbus_frame``; cycles: the
    bus is idle at ``max(accept) + mem_cycle`` (the golden cycle count), the read-out starts there
    and takes one clock per word, plus one (``ReadOut``)."""

    block = "pixelbus"
    inputs = ("i_pipe0", "i_pipe1")

    def signature(self) -> tuple[list[str], dict]:
        return factory_params(self.block)   # from the build cache: a warm sim pixelbus imports no HDL

    def dut(self, params: dict):
        return _read_out(super().dut(params), self.inputs, params["width"] * params["height"])

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        w, h = params["width"], params["height"]
        n = int(rng.integers(max(20, w * h // 2), 2 * w * h + 1))
        s, what = _stream(rng, w, h, n, int(rng.choice([1, 2, 2, 2])), params["z_bits"], params["n_banks"])
        return self.stimulus_of(params, s, what=f"{what}, seed {seed}")

    def stimulus_of(self, params: dict, stream: PixelStream, gaps=None, what: str = "") -> Stimulus:
        """``stream``'s writes as each pipeline's words (``gaps``: idle clocks before each write)."""
        aw = _addr_bits(params["width"] * params["height"])
        words, gs = {}, {}
        for p, port in enumerate(self.inputs):
            words[port], g = _port_words(stream, np.flatnonzero(stream.pipe == p), aw, gaps)
            if g is not None:
                gs[port] = g
        return Stimulus(words, gs, what=what, source=(stream, gaps))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        s, gaps = stim.source
        kw = {"mem_cycle": params["mem_cycle"], "n_banks": params["n_banks"]}
        acc = golden.pixelbus_accept_cycles(s, gaps=gaps, **kw)
        rgb, z = golden.pixelbus_frame(s, accept=acc, **kw)
        cycles = int(acc.max()) + params["mem_cycle"] + s.width * s.height + 1 if len(s) else None
        return Expected({"o": _frame_words(rgb, z, params["z_bits"])}, cycles=cycles)


class FrameBench(BusBench):
    """``pixelbus`` drawing one whole frame (``sim/snu/scene.py``): CLEAR, the two pipelines'
    writes each after its 16-bit producer gap, SWAP, the display buffer out on ``o`` and the
    schedule on ``o_sched`` (:class:`~rasterhw.sim.snu.frame_adapter.FrameAdapter`). Not the
    block's registered testbench (that is :class:`BusBench`); the frame runs it on the engines.
    Golden: ``golden_schedule`` and ``pixelbus_frame`` (``stim.source``: ``(stream, schedule)``)."""

    verilator_opt = "-O2"   # one run of ~17 M clocks: the clock loop outweighs the longer build

    def dut(self, params: dict):
        from rasterhw.sim.snu.frame_adapter import FrameAdapter  # Amaranth: when the block is built

        return FrameAdapter(Testbench.dut(self, params), self.inputs, params["width"] * params["height"])

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        return ("o", "o_sched")

    def stimulus_of(self, params: dict, stream: PixelStream, gaps=None, what: str = "", *, schedule=None) -> Stimulus:
        """Each pipeline's writes as ``{end, gap, write}`` words (``gaps``: the producer gaps, the
        first write's counted from the pipelines' release), then the end token; ``schedule``:
        ``sim/snu/scene.py: golden_schedule`` of the same stream and gaps."""
        aw = _addr_bits(params["width"] * params["height"])
        g = np.zeros(len(stream), np.int64) if gaps is None else np.asarray(gaps, dtype=np.int64)
        words = {}
        for p, port in enumerate(self.inputs):
            idx = np.flatnonzero(stream.pipe == p)
            fields = [(np.zeros(idx.size, np.int64), 1), (g[idx], GAP_BITS)] + payload_fields(stream, idx, aw)
            words[port] = _then_end(pack_fields(fields), sum(b for _, b in fields))
        return Stimulus(words, what=what, source=(stream, schedule))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        s, sched = stim.source
        rgb, z = golden.pixelbus_frame(s, accept=sched["accept"], mem_cycle=params["mem_cycle"],
                                       n_banks=params["n_banks"])
        return Expected({"o": _frame_words(rgb, z, params["z_bits"]), "o_sched": [int(sched[k]) for k in SCHEDULE]})
