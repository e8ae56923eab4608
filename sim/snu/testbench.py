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


#: the bank's commands in its testbench's stream (``PixelBusBank``'s ``Command``: CLEAR 0, SWAP 1)
CLEAR, SWAP = 0, 1


def _with_commands(bank):
    """The bank with one write stream ``i`` of ``{write, is_cmd, cmd}`` words, in order: a word with
    ``is_cmd`` goes to ``i_cmd`` (``cmd``: CLEAR or SWAP), the others to ``i``; so the testbench
    orders writes and commands exactly, and the bank sees each when it is offered (its own rule,
    "commands win", is then never a race). Read port, ``busy`` and ``draw_buf`` pass through."""
    from amaranth import Module, Mux
    from amaranth.lib import data, stream, wiring
    from amaranth.lib.wiring import In, Out

    w = len(bank.i.payload.as_value())
    word = data.StructLayout({"write": w, "is_cmd": 1, "cmd": 1})   # the write in the low bits

    class BankWithCommands(wiring.Component):
        def __init__(self):
            super().__init__({"i": In(stream.Signature(word)), "rd_addr": In(len(bank.rd_addr)), "rd_buf": In(1),
                              "rd_rgb": Out(len(bank.rd_rgb)), "rd_z": Out(len(bank.rd_z)), "busy": Out(1)})

        def extra_verilog(self) -> str:
            return bank.extra_verilog()

        def elaborate(self, platform):
            m = Module()
            m.submodules.bank = bank
            cmd = self.i.payload.is_cmd
            m.d.comb += [
                bank.i.payload.as_value().eq(self.i.payload.write), bank.i.valid.eq(self.i.valid & ~cmd),
                bank.i_cmd.payload.as_value().eq(self.i.payload.cmd), bank.i_cmd.valid.eq(self.i.valid & cmd),
                self.i.ready.eq(Mux(cmd, bank.i_cmd.ready, bank.i.ready)),
                bank.rd_addr.eq(self.rd_addr), bank.rd_buf.eq(self.rd_buf),
                self.rd_rgb.eq(bank.rd_rgb), self.rd_z.eq(bank.rd_z), self.busy.eq(bank.busy)]
            return m

    return BankWithCommands()


def _bank_read_out(bank, depth: int):
    """:func:`_with_commands` behind ``ReadOut``: both RGB buffers out, the draw buffer's ``depth``
    words first (``rd_buf`` 0), then the display buffer's (``rd_buf`` 1), each ``{rgb, z}``."""
    from amaranth import Cat, Mux
    from rasterhw.sim.engines.readout import ReadOut

    def address(m, b, addr):
        second = addr >= depth
        m.d.comb += [b.rd_addr.eq(Mux(second, addr - depth, addr)), b.rd_buf.eq(second)]

    return ReadOut(_with_commands(bank), ports=("i",), words=2 * depth, address=address,
                   data=lambda b: Cat(b.rd_z, b.rd_rgb))


def bank_frame(depth: int, stream: PixelStream, commands) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The golden bank after ``stream``'s writes and ``commands`` (``[(k, CLEAR or SWAP)]``: before
    write ``k``, in order): ``(rgb of buffer 0 and 1, (2, depth); z; draw)``. A write is kept when
    its Z is strictly greater than the stored Z (``pixelbus_frame``'s rule, the Z compare
    ``PixelBusBank`` makes); CLEAR sets every Z and the draw buffer's RGB to 0, SWAP exchanges
    the draw and display buffers (``Command``'s words: "Z := 0 (far), draw-buffer RGB := 0
    (black)"; "exchange draw and display RGB buffers")."""
    rgb, z, draw = np.zeros((2, depth), np.int64), np.zeros(depth, np.int64), 0
    at = {}
    for k, c in commands:
        at.setdefault(int(k), []).append(c)
    for k in range(len(stream) + 1):
        for c in at.get(k, ()):
            if c == CLEAR:
                z[:] = 0
                rgb[draw] = 0
            else:
                draw ^= 1
        if k < len(stream):
            a = int(stream.addr[k])
            if int(stream.z[k]) > z[a]:
                z[a], rgb[draw, a] = int(stream.z[k]), int(stream.rgb[k])
    return rgb, z, np.int64(draw)


class BankBench(Testbench):
    """``pixelbus-bank``: pixel writes (bank-local address, RGB, Z) and commands (CLEAR, SWAP) in
    on ``i`` in one ordered stream (:func:`_with_commands`), back to back; both RGB buffers and Z
    out (``o``, ``2 * depth`` words: the draw buffer, then the display buffer). Golden:
    :func:`bank_frame` (the writes in order with the strict Z test, the commands between them),
    and the cycle count of one bank (:func:`bank_cycles`: one write per memory cycle, the block's
    documented throughput; a CLEAR ``depth`` clocks, a SWAP one; the read-out once the last
    memory cycle ended). The bus's golden cycle model (two pipelines' slots) is not one bank's."""

    block = "pixelbus-bank"

    def dut(self, params: dict):
        return _bank_read_out(super().dut(params), params["depth"])

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        """A random stream (:func:`_stream`) and, drawn after it, one to four commands at random
        places (CLEAR or SWAP, as likely), so a seed's writes are those it had before commands."""
        rng = np.random.default_rng(seed)
        s, what = _stream(rng, params["depth"], 1, int(rng.integers(40, 200)), 1, params["z_bits"], 1)
        n = int(rng.integers(1, 5))
        cmds = sorted(zip(rng.integers(0, len(s) + 1, n).tolist(), rng.integers(0, 2, n).tolist(), strict=True),
                      key=lambda kc: kc[0])
        said = ", ".join(f"{'CLEAR' if c == CLEAR else 'SWAP'} before write {k}" for k, c in cmds)
        return self.stimulus_of(params, s, what=f"{what}, {said}, seed {seed}", commands=cmds)

    def stimulus_of(self, params: dict, stream: PixelStream, gaps=None, what: str = "", *,
                    commands=()) -> Stimulus:
        """``stream`` (one pipeline, ``addr`` bank-local, a ``depth`` x 1 frame) and ``commands``
        (``[(k, CLEAR or SWAP)]``: before write ``k``, in order) as the bank's words (``gaps``: idle
        clocks before each write; none before a command)."""
        cmds = sorted(((int(k), int(c)) for k, c in commands), key=lambda kc: kc[0])   # stable: in order
        n = len(stream)
        pos = np.arange(n) + np.searchsorted([k for k, _ in cmds], np.arange(n), side="right")
        total = n + len(cmds)
        is_cmd, cmd = np.ones(total, np.int64), np.zeros(total, np.int64)
        is_cmd[pos] = 0
        cmd[is_cmd == 1] = [c for _, c in cmds]
        aw = _addr_bits(params["depth"])
        fields = [(np.zeros(total, np.int64), 1), (cmd, 1), (is_cmd, 1)]
        for col, bits in payload_fields(stream, np.arange(n), aw):
            full = np.zeros(total, np.int64)
            full[pos] = col
            fields.append((full, bits))
        words = _then_end(pack_fields(fields), sum(b for _, b in fields))
        g = None
        if gaps is not None:
            g = np.zeros(total + 1, np.int64)
            g[pos] = np.asarray(gaps, dtype=np.int64)
        return Stimulus({"i": words}, {} if g is None else {"i": g}, what=what, source=(stream, cmds))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        s, cmds = stim.source
        rgb, z, draw = bank_frame(params["depth"], s, cmds)
        words = _frame_words(rgb[draw], z, params["z_bits"]) + _frame_words(rgb[1 - draw], z, params["z_bits"])
        return Expected({"o": words}, cycles=bank_cycles(params, stim))


def bank_cycles(params: dict, stim: Stimulus) -> int:
    """The edges of a bank run with ``o`` always ready (``ReadOut``'s timing): write ``k`` is
    offered ``gap`` clocks after the edge following write ``k - 1``'s accept and accepted once the
    bank is free, ``mem_cycle`` clocks after that accept (``PixelBusBank``: "one write per
    ``mem_cycle`` clocks"); the end token is taken when offered; the sweep starts at the first
    clock with the token seen and the last memory cycle over, and gives word ``j`` at the edge
    after it plus ``j``: the cycles are that start + ``depth`` + 1 (added for mutation coverage,
    docs/mutation.md: the bank's memory-cycle counter was unchecked). A command is taken like a
    write, once the bank is free, and keeps it busy: a CLEAR for ``depth`` clocks after the clock
    it is taken in (one word a clock), a SWAP for none; the read-out is ``2 * depth`` words."""
    s, cmds = stim.source
    m, depth, g = params["mem_cycle"], params["depth"], stim.gaps_of("i")
    busy = np.full(len(s) + len(cmds), m, np.int64)   # clocks from a word's accept to the next possible one
    pos = np.arange(len(s)) + np.searchsorted([k for k, _ in cmds], np.arange(len(s)), side="right")
    is_cmd = np.ones(busy.size, bool)
    is_cmd[pos] = False
    busy[is_cmd] = [depth + 1 if c == CLEAR else 1 for _, c in cmds]
    n, words = busy.size, 2 * depth
    if n == 0:
        return int(g[0]) + 1 + words + 1
    accept = int(g[0]) + int(np.maximum(busy[:-1], 1 + g[1:n]).sum())
    start = max(accept + 1 + int(g[n]) + 1, accept + int(busy[-1]))
    return start + words + 1


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
        # the display words as packed rows (``sim/packed.py``): compared with the Verilator engine's
        # rows (``frame_job`` asks for them) in NumPy, without a Python int per pixel
        rows = pack_fields([(rgb.ravel(), RGB_BITS), (z.ravel(), params["z_bits"])])
        return Expected({"o": rows, "o_sched": [int(sched[k]) for k in SCHEDULE]})
