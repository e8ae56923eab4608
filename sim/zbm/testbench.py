# amaranth: UnusedElaboratable=no
"""Testbenches of the ZB/M blocks (``sim/testbench.py``): what each block takes and what the golden
model says it gives; the engines (``sim/engines/``) run them."""

from __future__ import annotations

import re

import numpy as np
from rasterhw.golden_model import zbm as G
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.zbm import formats as F
from rasterhw.golden_model.zbm.stimulus import (
    first_triangles,
    multi_line_segments,
    random_doublez,
    random_triangles,
)
from rasterhw.golden_model.zbm.words import (
    doublez_words,
    edge_pair_rows,
    edge_pair_words,
    merge_rows,
    merge_words,
    packets,
    pixel2_words,
    rows_to_samples,
    segment_words,
)
from rasterhw.sim import registry
from rasterhw.sim.engines.verilog import merge_identical_modules
from rasterhw.sim.engines.verilog_cache import factory_params
from rasterhw.sim.testbench import Clock, Expected, Run, Stimulus, Testbench

__all__ = ["RESET_EDGES", "ChipBench", "LoopBench", "MergerBench", "PixelBench", "SeggenBench", "UnitBench",
           "bench_clocks", "deal", "pixel_visits", "random_gaps", "unit_watchdog"]


def random_gaps(n: int, seed: int | None, *, p_idle: float = 0.3, max_gap: int = 4) -> np.ndarray:
    """Idle clocks before each of ``n`` words: 0 with probability ``1 - p_idle``, else 1..max_gap; ``seed=None``: none
    (the ZB/M cocotb cross-check in ``tests/zbm_cocotb/`` plays the same)."""
    if seed is None:
        return np.zeros(n, np.int64)
    rng = np.random.default_rng(seed)
    return rng.integers(1, max_gap + 1, n) * (rng.random(n) < p_idle)


#: rising edges of each clock the cocotb benches hold their reset for (``rasterhw_reset #(.CYCLES(6))``)
RESET_EDGES = 6


def bench_clocks(ratio: tuple[int, int], phase: int = 1) -> dict[str, Clock]:
    """The generic engine's separate clocks (``engines.run(..., clocks=...)``, 1 ns units) of a unit run at
    segment : merge half periods ``ratio`` (ns) with the merge clock ``phase`` (0 or 1) ns behind, timed as
    the cocotb unit bench's Verilog-side clocks after its reset (``tests/zbm_cocotb/``: ``rasterhw_two_clocks``
    raises ``clk`` at 1 + (2k + 1) * segment half ns and ``mclk`` ``phase`` ns later on its own half
    period; the engine has no reset, so edge 0 of each domain is the bench's edge :data:`RESET_EDGES`)."""
    sh, mh = ratio
    if phase not in (0, 1):
        raise RasterhwError(f"merge clock phase must be 0 or 1 ns, not {phase!r}")
    if not (isinstance(sh, int) and isinstance(mh, int) and sh >= 1 and mh >= 1):
        raise RasterhwError(f"clock ratio must be two positive integer half periods (ns), not {ratio!r}")
    return {"sync": Clock(sh, 1 + (2 * RESET_EDGES + 1) * sh), "merge": Clock(mh, 1 + phase + (2 * RESET_EDGES + 1) * mh)}


def unit_watchdog(total_words: int, *, width: int, height: int, stall: int = 0,
                  ratio: tuple[int, int] = (5, 5)) -> int:
    """A unit run's watchdog in segment clocks: generously above any frame this design can take with
    ready always high and equal clocks, times the expected slow-down of the back-pressure (ready high in
    ``256 - stall`` of 256 merge clocks) and of a merge clock slower than the segment clock (``ratio``: half periods)."""
    base = 200 * (total_words + 64) + 40 * height * (width + 64)
    slow = 256 / max(1, 256 - stall) * max(1.0, ratio[1] / ratio[0])
    return min(int(base * max(1.0, slow)), 2**31 - 1)   # the cocotb bench's MAXCYC is a Verilog integer


class SeggenBench(Testbench):
    """``zbm-seggen``: edge-pair words in (``i``), every scan line's segment words out (``o``), as
    ``golden_model/zbm/seggen.py: segment_generator`` gives them. Two random frames, one after
    the other (the block counts frames): a colour frame and a mapping frame (an edge pair carries
    its mode; the mapping frame's pairs have six attribute channels, the colour frame's five), each
    of 2..40 random screen triangles (seeded), as many edge pairs as the memory holds at most."""

    block = "zbm-seggen"

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        w, h = params["width"], params["height"]
        frames, ns = [], []
        for mode in (F.MODE_COLOUR, F.MODE_MAPPING):
            n = int(rng.integers(2, 41))
            tris = random_triangles(rng, n, w, h, size=float(rng.uniform(3, max(4, min(w, h) / 2))))
            eps = G.edge_pairs(tris, mode=mode)
            while len(eps) and G.max_active_edge_pairs(eps)[0] > params["capacity"]:
                eps = eps.take(np.arange(len(eps) - 1))   # the frame must fit the memory
            frames.append(eps)
            ns.append(n)
        return Stimulus({"i": [wd for eps in frames for wd in edge_pair_words(eps)]},
                        what=f"{ns[0]} random triangles in colour, then {ns[1]} in mapping mode, seed {seed}",
                        source=frames)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        h = params["height"]
        out = []
        for eps in stim.source:
            segs = G.segment_generator(eps, h, width=params["width"], capacity=params["capacity"])
            out += [wd for y in range(h) for wd in segment_words(segs, y)]
        return Expected({"o": out})


class UnitBench(Testbench):
    """``zbm-unit`` (the head unit of a chain, or ``units`` chained units: parameter ``units``,
    default 1): edge-pair words in (``i``; unit ``k`` of a chain: ``units[k].i``), every chip's
    merge-bus words out (``o_merge[c]``, the last unit's in a chain; chip ``c`` owning columns
    ``c, c + I, ...``, line by line), the double-Z samples of ``golden_model/zbm/render.py:
    render_zbm``. The merge clock runs with the segment clock, or at any ratio and phase as a run's
    separate clocks (``engines.run(..., clocks=...)``; :func:`bench_clocks`: the cocotb bench's). A random frame: 2..40 random
    screen triangles (seeded), the first ones that fit the active-edge-pair memory; a scene: :meth:`scene_stimulus` (``rasterhw sim zbm``, the soak).

    The back-pressure of slot ``c`` is the cocotb unit bench's (``cocotb_tests/zbm/tb_zbm_unit.v``: seed ``0x9E3779B9 ^
    (7919 seed + 104729 c + 1)``), so a run equals that bench's, stalls included. The speed build (``build={"speed": True}``):
    identical modules merged, the pixel processor kept out of line (:meth:`sim_verilog`); its gcc profile is trained on c50."""

    block = "zbm-unit"
    domains = ("sync", "merge")
    port_domains = {"o_merge": "merge"}

    def params(self, **given) -> dict:
        units = given.pop("units", 1)
        if not isinstance(units, (int, np.integer)) or isinstance(units, bool) or not 1 <= units <= 16:
            raise RasterhwError(f"units must be an integer in 1..16, not {units!r}")
        return {**super().params(**given), "units": int(units)}

    def signature(self) -> tuple[list[str], dict]:
        return factory_params(self.block)   # from the build cache: a warm sim zbm imports no HDL

    def dut(self, params: dict):
        p = {k: v for k, v in params.items() if k != "units"}
        factory = registry.load(registry.blocks()[self.block])
        if params.get("units", 1) == 1:
            return factory(**p)
        from rasterhw.hdl.zbm.chain import ZbmChain  # here, as Amaranth: a warm run builds no block

        return ZbmChain([factory(**{**p, "head": k == 0}) for k in range(params["units"])])

    def _prefix(self, params: dict, k: int) -> str:
        return "" if params.get("units", 1) == 1 else f"units[{k}]."

    def inputs_of(self, params: dict) -> tuple[str, ...]:
        return tuple(f"{self._prefix(params, k)}i" for k in range(params.get("units", 1)))

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        last = self._prefix(params, params.get("units", 1) - 1)
        return tuple(f"{last}o_merge[{c}]" for c in range(params["interleave"]))

    def domain_of(self, port: str) -> str:
        return "merge" if "o_merge" in port else "sync"

    def status(self, dut, params: dict) -> dict:
        """``frames_ok``: every unit finished exactly one frame; ``overflow``: a unit's sticky overflow."""
        from amaranth.hdl import Cat

        units = dut.units if params.get("units", 1) > 1 else [dut]
        return {"frames_ok": Cat(*[u.frames == 1 for u in units]).all(), "overflow": Cat(*[u.overflow for u in units]).any()}

    def sink_seed(self, params: dict, port: int, seed: int) -> int:
        return 0x9E3779B9 ^ ((seed * 7919 + port * 104729 + 1) & 0xFFFF_FFFF)

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        w, h = params["width"], params["height"]
        n = int(rng.integers(2, 41))
        tris = random_triangles(rng, n, w, h, size=float(rng.uniform(3, max(4, min(w, h) / 2))))
        while len(tris.xy) > 1 and G.max_active_edge_pairs(G.edge_pairs(tris))[0] > params["capacity"]:
            tris = first_triangles(tris, len(tris.xy) - 1)
        return self.scene_stimulus(params, deal(G.edge_pairs(tris), params["units"]),
                                   what=f"{len(tris.xy)} random triangles, seed {seed}")

    def scene_stimulus(self, params: dict, eps_per_unit: list, *, gap_seed: int | None = None,
                       what: str = "") -> Stimulus:
        """Unit ``k``'s edge pairs (:func:`deal`: a scene's, as ``render_zbm`` deals them) as its
        edge-pair words, packed rows (``edge_pair_rows``); ``gap_seed``: random idle gaps (:func:`random_gaps`
        over all units' words in order, as the cocotb bench plays them; None: none)."""
        ins = self.inputs_of(params)
        if len(eps_per_unit) != len(ins):
            raise RasterhwError(f"zbm-unit: {len(eps_per_unit)} edge-pair lists for {len(ins)} units")
        words = [edge_pair_rows(e) for e in eps_per_unit]
        gaps = random_gaps(sum(map(len, words)), gap_seed).tolist()
        at = np.cumsum([0] + [len(w) for w in words])
        return Stimulus(dict(zip(ins, words, strict=True)),
                        gaps={p: gaps[at[k]:at[k + 1]] for k, p in enumerate(ins)} if gap_seed is not None else {},
                        what=what, source=list(eps_per_unit))

    def expect(self, params: dict, stim: Stimulus, segments: list | None = None) -> Expected:
        """Every slot's merge words of ``chain_frame``'s frame, as packed rows (``merge_rows``);
        ``segments``: each unit's segments, when the caller has them (``chain_frame``)."""
        i = params["interleave"]
        frame = G.chain_frame(stim.source, params["width"], params["height"], capacity=params["capacity"],
                              segments=segments)
        g0, g1 = doublez_words(frame)
        outs = self.outputs_of(params)
        return Expected({outs[c]: merge_rows(g0[:, c::i], g1[:, c::i]) for c in range(i)}, golden=frame)

    def frame(self, params: dict, words: dict) -> tuple[np.ndarray, np.ndarray]:
        """The merge words of every slot (ints or packed rows) as the frame's (s0, s1) (H, W) uint64
        samples (all ones where a slot gave no word, as the benches' frame memories)."""
        i, w, h = params["interleave"], params["width"], params["height"]
        s0 = np.full((h, w), ~np.uint64(0), np.uint64)
        s1 = s0.copy()
        for c, port in enumerate(self.outputs_of(params)):
            npx = len(range(c, w, i))
            got = words.get(port, [])[:h * npx]
            n = len(got) // npx * npx
            if isinstance(got, np.ndarray):
                lo, hi = rows_to_samples(got[:n])
            else:
                lo = np.fromiter((x & _M64 for x in got[:n]), np.uint64, n)
                hi = np.fromiter((x >> 64 for x in got[:n]), np.uint64, n)
            s0[:n // npx, c::i], s1[:n // npx, c::i] = lo.reshape(-1, npx), hi.reshape(-1, npx)
        return s0, s1

    def line_cycles(self, params: dict, run: Run) -> list[int]:
        """Per line ``y``: the segment clocks until every slot had given line ``y`` (the segment-clock
        edges before the merge edge after its last word; one clock: that word's edge + 1), the
        cocotb bench's per-line log."""
        i, w, h = params["interleave"], params["width"], params["height"]
        out = np.zeros(h, np.int64)
        for c, port in enumerate(self.outputs_of(params)):
            npx = len(range(c, w, i))
            st = np.asarray(run.stamps[port][:h * npx], np.int64)
            out = np.maximum(out, [run.cycles_at(port, int(e) + 1) for e in st[npx - 1::npx]])
        return out.tolist()

    def sim_verilog(self, params: dict, text: str) -> str:
        """Each identical module once, the pixel processor kept out of line (``_pixel_processor``):
        at I = 8, 132 modules -> 27, the same circuit."""
        return merge_identical_modules(text, no_inline=_pixel_processor)

    def train_stimulus(self, params: dict) -> Stimulus:
        """c50 (:data:`TRAIN_SCENE`; the frames a profile is checked on are others) at the block's size."""
        tris = run_geometry(build_scene(TRAIN_SCENE), params["width"], params["height"])
        return self.scene_stimulus(params, deal(G.edge_pairs(tris), params["units"]), what=f"scene {TRAIN_SCENE}")


def deal(eps, units: int) -> list:
    """A frame's edge pairs dealt to ``units`` units as ``render_zbm`` deals its triangles
    (triangle i -> unit i % units)."""
    return [eps.take(np.flatnonzero(eps.tag % units == k)) for k in range(units)]


_M64 = (1 << 64) - 1
#: the scene a unit's gcc profile is trained on
TRAIN_SCENE = "c50"


def _pixel_processor(name: str, copies: int, size: int) -> bool:
    """The module the speed build keeps out of line: the loop's pixel processor (``hdl/zbm/loop.py``
    submodules ``pp0`` ... ``pp7``; 8 x I copies of one circuit). Measured on c300, I = 8, with g++
    -O2 and PGO: out of line 0.73-0.75 s of CPU per frame, every module inlined 0.76-0.87 s; without
    PGO the pixel processor alone out of line was slower than inlined (docs/zbm.md, Simulation speed)."""
    return re.search(r"\.loop\.pp\d+$", name.strip()) is not None


class MergerBench(Testbench):
    """``zbm-merger`` (the chip's merger, its PIXEL2 word): own double-Z words in on the segment
    side (``i_own``), the upstream chip's on the merge side (``i_merge``), the nearest two of the
    four samples of each pair out (``o_merge``), as ``golden_model/zbm/merger.py: merge`` (upstream
    first on equal Z). Random pixels with Z ties and empty samples (``random_doublez``). Both
    clocks run together unless a run gives each its own; ``rasterhw mutate`` runs every mutant a
    third time at segment : merge half periods 5 : 3 (:attr:`mutation_clocks`: the asynchronous
    FIFO's Gray pointers and synchronisers only matter when the clocks differ); the free-running
    unrelated clocks are the proof's (``sim/zbm/proof.py``) and the cocotb bench's."""

    block = "zbm-merger"
    inputs = ("i_own", "i_merge")
    outputs = ("o_merge",)
    domains = ("sync", "merge")
    port_domains = {"i_merge": "merge", "o_merge": "merge"}
    mutation_clocks = {"sync": (3, 0), "merge": (7, 2)}

    def params(self, **given) -> dict:
        p = super().params(**given)
        if (p["z_bits"], p["colour_bits"]) != (F.Z_BITS, F.COLOUR_BITS):
            raise RasterhwError("zbm-merger testbench: the golden words are the full PIXEL2 "
                                f"(z_bits {F.Z_BITS}, colour_bits {F.COLOUR_BITS})")
        return p

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        n = int(rng.integers(60, 200))
        own, up = random_doublez(rng, n), random_doublez(rng, n)
        # every other pixel's depths on a random base of the Z range, the same for both inputs (the
        # ties stay; every bit of the 24-bit compares and of the words through the FIFO toggles)
        base = rng.integers(0, F.Z_MAX_SAMPLE - 64, n) * (np.arange(n) % 2)
        for d in (own, up):
            d.z[:] = np.where(d.z == F.Z_EMPTY, d.z, d.z + base[:, None])
        return Stimulus({"i_own": merge_words(*doublez_words(own)), "i_merge": merge_words(*doublez_words(up))},
                        what=f"{n} random pixel pairs, seed {seed}", source=(own, up))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        own, up = stim.source
        return Expected({"o_merge": merge_words(*doublez_words(G.merge(up, own)))})


def _lines(rng, params: dict, chip_slots: int, *, most: int = 12) -> tuple[list[tuple[G.Segments, int]], int]:
    """Random scan lines, as ``(segments, y)``: a colour frame, then a mapping frame (each packet
    carries its mode, so both modes' field paths run in every stimulus), each of 2..4 lines of
    2..``most`` random segments (one line of the first frame empty), then :data:`WIDE_LINES` lines
    of ``most / 2 .. 2 most`` segments whose values span the slot (:func:`_widen`); every other line's depths moved
    by a random base (they still collide, and every bit of the 24-bit Z compares toggles); and a chip slot
    ``0 <= chip < chip_slots`` (seeded)."""
    w = params["width"]
    chip = int(rng.integers(0, min(chip_slots, w)))
    out = []
    for mode in (F.MODE_COLOUR, F.MODE_MAPPING):
        counts = [int(c) for c in rng.integers(2, most + 1, int(rng.integers(2, 5)))]
        if mode == F.MODE_COLOUR:
            counts[int(rng.integers(0, len(counts)))] = 0
        segs = multi_line_segments(rng, counts + [int(c) for c in rng.integers(most // 2, 2 * most + 1, WIDE_LINES)], w, mode)
        _widen(rng, segs, int(segs.line_start[len(counts)]))
        for y in range(1, len(counts) + WIDE_LINES, 2):   # depths that collide, anywhere in the Z range
            at = slice(segs.line_start[y], segs.line_start[y + 1])
            segs.val[at, 0] += int(rng.integers(0, F.Z_MAX_SAMPLE - 64)) << F.ATTR_FRAC
        out += [(segs, y) for y in range(len(segs.line_start) - 1)]
    return out, chip


#: lines of a loop, pixel or chip frame whose segments have values over the whole slot
WIDE_LINES = 3
#: most segments of a line in the loop's and the pixel processor's stimulus: a processor owns one
#: chip pixel in 8, so at 12 (the chip's) processor 0 of a 128-pixel line at I = 8 saw 12 visits
#: in all (seed 1); at 96 it sees a few hundred. The loop takes half (its pysim run, 8 processors,
#: took 109 s at 96 in ``tests/test_engines.py``)
DENSE = 96


def _widen(rng, segs: G.Segments, first: int) -> None:
    """Segments ``first ..``: in each channel a third keep the near range, a third get one high
    bit added (``±2**k``, ``k`` 24..53: the value clamps, and any fault that drops that bit of the
    stored fields' rounding add, ``hdl/zbm/pixel.py: flit_to_sample_field``, brings it back in
    range), a third a value with its top bit anywhere from bit 16 to 53 (every bit of the add and
    of the clamps' compares toggles). Half the segments also get wide increments. No value of a
    line leaves the 56-bit slot (|value| < 2**55, |increment| < 2**49, 24 pixels)."""
    n, c = segs.val[first:].shape
    sign = np.where(rng.random((n, c)) < 0.5, -1, 1)
    kind = rng.integers(0, 3, (n, c))
    one = np.left_shift(1, rng.integers(F.ATTR_FRAC, 54, (n, c)))
    top = rng.integers(16, 54, (n, c))
    spread = rng.integers(0, 1 << 62, (n, c)) >> (62 - top)
    near = segs.val[first:]
    segs.val[first:] = np.where(kind == 0, near, np.where(kind == 1, near + sign * one, sign * spread))
    top = rng.integers(8, 49, (n, c))
    inc = (rng.integers(0, 1 << 62, (n, c)) >> (62 - top)) * np.where(rng.random((n, c)) < 0.5, -1, 1)
    segs.inc[first:] = np.where(rng.random((n, 1)) < 0.5, inc, segs.inc[first:])


def _packet_word(flits: list[int]) -> int:
    """8 loop flits -> one ``PACKET`` word (flit ``k`` in bits ``112 k ..``)."""
    return sum(f << (F.LOOP_BITS * k) for k, f in enumerate(flits))


#: the end-of-line token of the loop and pixel benches: a packet whose header has ``len == 0``
_EOL = _packet_word([F.PKT_HEADER.pack(len=0)] + [0] * (F.PACKET_FLITS - 1))


def _line_words(buf: G.DoubleZ, n: int) -> list[int]:
    """A chip line's PIXEL2 words padded with empty pixels to ``n`` (a chip with ``chip > 0``
    may own one pixel fewer than the loop's memory holds)."""
    w = pixel2_words(buf)
    return w + pixel2_words(G.DoubleZ.empty((n - len(w),))) if n > len(w) else w


def pixel_visits(flits: list[int], index: int, interleave: int) -> list[list[int]]:
    """The packet ``flits`` (from ``golden_model/zbm/words.py: packets``) as it reaches pixel
    processor ``index`` on the ring, once per pixel it owns there: after ``h`` hops the header
    has ``x + h * dx``, ``len - h`` and every channel ``value + h * inc`` (the loop's 56-bit adds:
    ``golden_model/zbm/chip.py: chip_scanline``); processor ``index`` owns chip pixels
    ``q = x // interleave`` with ``q % 8 == index``."""
    hdr = F.PKT_HEADER.unpack(flits[0])
    chans = [F.FLIT.unpack(f) for f in flits[1:]]
    q0 = hdr["x"] // interleave
    out = []
    for h in range(hdr["len"]):
        if (q0 + h) % F.PP_PER_CHIP != index:
            continue
        head = F.PKT_HEADER.pack(**{**hdr, "x": hdr["x"] + h * hdr["dx"], "len": hdr["len"] - h})
        out.append([head] + [F.FLIT.pack(value=int(F.wrap(c["value"] + h * c["inc"])), inc=c["inc"]) for c in chans])
    return out


class ChipBench(Testbench):
    """``zbm-chip``: one chip's segment words in (``i_seg``, line by line with end-of-line
    records: ``golden_model/zbm/words.py: segment_words``), the upstream chip's double-Z words
    in (``i_merge``, random pixels with ties and empty samples), the merged line out (``o_merge``),
    as ``merge(upstream, chip_scanline(...))`` gives it. A random frame: 4..7 lines of random
    segments (one line empty), colour or mapping mode; the chip slot is the block's parameter
    ``chip``. Both clocks run together here (the clock ratios stay with the cocotb bench)."""

    block = "zbm-chip"
    inputs = ("i_seg", "i_merge")
    outputs = ("o_merge",)
    domains = ("sync", "merge")
    port_domains = {"i_merge": "merge", "o_merge": "merge"}

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        lines, _ = _lines(rng, params, 1)
        i, c, w = params["interleave"], params["chip"], params["width"]
        npx = -(-(w - c) // i)
        ups = [random_doublez(rng, npx) for _ in lines]
        return self._stimulus(lines, ups, what=f"{len(lines)} lines of random segments, seed {seed}")

    def status(self, dut, params: dict) -> dict:
        """``lines``: scan lines the chip has finished (its ``lines`` counter)."""
        return {"lines": dut.lines}

    def scene_stimulus(self, params: dict, segs, ups: list, *, what: str = "") -> Stimulus:
        """Lines ``0 .. len(ups) - 1`` of ``segs`` (a frame's golden segments) on the segment port,
        ``ups[y]`` (the chip's pixels of line ``y``) on the upstream merge port."""
        return self._stimulus([(segs, y) for y in range(len(ups))], ups, what=what)

    def _stimulus(self, lines: list, ups: list, *, what: str) -> Stimulus:
        """``lines[k]`` = ``(segments, y)`` (line ``y`` of a frame) and ``ups[k]`` (its upstream
        pixels) for each line ``k`` the chip takes."""
        words = [wd for segs, y in lines for wd in segment_words(segs, y)]
        return Stimulus({"i_seg": words, "i_merge": [wd for u in ups for wd in pixel2_words(u)]},
                        what=what, source=(lines, ups))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        lines, ups = stim.source
        i, c, w = params["interleave"], params["chip"], params["width"]
        out = []
        for (segs, y), up in zip(lines, ups, strict=True):
            own, _ = G.chip_scanline(segs, y, c, i, w)
            out += pixel2_words(G.merge(up, own))
        return Expected({"o_merge": out})


class LoopBench(Testbench):
    """``zbm-loop`` (segment processor + 8 pixel processors) in :class:`LineBench`: one chip's
    packets in (``i``, line by line, each line ended by a ``len == 0`` token; the chip slot is
    drawn from the seed), every finished line out (``o``, the loop's ``chip_pixels`` words), as
    ``golden_model/zbm/chip.py: chip_scanline`` gives it."""

    block = "zbm-loop"

    def dut(self, params: dict):
        from rasterhw.sim.zbm.line_bench import LineBench

        block = registry.load(registry.blocks()[self.block])(**params)
        return LineBench(block, block.chip_pixels)

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        lines, chip = _lines(rng, params, params["interleave"], most=DENSE // 2)
        words = [wd for segs, y in lines
                 for wd in [_packet_word(p) for p in packets(segs, y, chip, params["interleave"])] + [_EOL]]
        return Stimulus({"i": words}, what=f"{len(lines)} lines of random segments, chip {chip}, seed {seed}",
                        source=(lines, chip, len(lines)))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        lines, chip, _ = stim.source
        i, w = params["interleave"], params["width"]
        n = -(-w // i)
        return Expected({"o": [wd for segs, y in lines for wd in _line_words(G.chip_scanline(segs, y, chip, i, w)[0], n)]})


class PixelBench(Testbench):
    """``zbm-pixel`` (pixel processor ``index``) in :class:`LineBench`: the visits of one chip's
    packets to this processor in (``i``: :func:`pixel_visits`, line by line, each line ended by
    a ``len == 0`` token; the chip slot is drawn from the seed), its line memory out (``o``,
    ``depth`` words: chip pixels ``index, index + 8, ...``), as ``chip_scanline`` gives them."""

    block = "zbm-pixel"

    def dut(self, params: dict):
        from rasterhw.sim.zbm.line_bench import LineBench

        block = registry.load(registry.blocks()[self.block])(**params)
        return LineBench(block, block.depth)

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng = np.random.default_rng(seed)
        lines, chip = _lines(rng, params, params["interleave"], most=DENSE)
        i, k = params["interleave"], params["index"]
        words = [wd for segs, y in lines
                 for wd in [_packet_word(v) for p in packets(segs, y, chip, i) for v in pixel_visits(p, k, i)] + [_EOL]]
        return Stimulus({"i": words}, what=f"{len(lines)} lines of random segments, chip {chip}, seed {seed}",
                        source=(lines, chip, len(lines)))

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        lines, chip, _ = stim.source
        i, w, k = params["interleave"], params["width"], params["index"]
        depth = max(1, -(-w // (F.PP_PER_CHIP * i)))
        n = depth * F.PP_PER_CHIP
        return Expected({"o": [wd for segs, y in lines
                               for wd in _line_words(G.chip_scanline(segs, y, chip, i, w)[0], n)[k::F.PP_PER_CHIP]]})
