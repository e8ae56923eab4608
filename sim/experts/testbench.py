# amaranth: UnusedElaboratable=no
"""Testbenches of the EXPERTS blocks (``sim/testbench.py``): the PXP, the DMM/P and the two
together, fed with the golden SLP's segment words of a random frame."""

from __future__ import annotations

import numpy as np
from amaranth import EnableInserter, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from rasterhw.golden_model.experts.formats import ACC_EXTRA
from rasterhw.golden_model.experts.model import render_frame
from rasterhw.golden_model.experts.pxp_cycles import line_segments
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scenes import build_scene
from rasterhw.sim import registry
from rasterhw.sim.experts.pxp_jobs import (
    RANGE_BITS,
    SEG_BITS,
    SPAN_BITS,
    job_list,
    range_word,
    span_job_list,
)
from rasterhw.sim.testbench import Expected, Stimulus, Testbench

__all__ = ["DmmBench", "GroupBench", "PxpBench", "PxpCoherentBench", "PxpSpanBench", "PxpUnitBench", "RangeFromTokens", "SlpBench",
           "SlpSetupBench", "job_stimulus", "setup_words", "slp_words"]


class RangeFromTokens(wiring.Component):
    """Bench adapter: a PXP (or DMM/P + PXP) whose line range ``lo``/``hi`` rides on the stimulus,
    and its per-line log.

    ``i`` carries ``{flag, next_hi[10:0], next_lo[9:0], word}`` (``sim/experts/pxp_jobs.py``). The
    first word is a range word (``flag`` set, :func:`~rasterhw.sim.experts.pxp_jobs.range_word`):
    the adapter takes it itself, puts its range on ``lo``/``hi``, and only then starts the block's
    clock (``EnableInserter``: the block's edge ``k`` is the run's edge ``k + 1``, so the first
    line's range is there when the block samples it, on its first edge). Every other word goes to
    the block, and when a ``last`` token is taken the range of the next line is put on
    ``lo``/``hi`` (which the block samples when that line starts). No register on the stream: the
    block sees every word in the cycle the bench offers it.

    ``log`` carries the block's finish-time counter ``line_cycles`` on the edge its line count
    ``lines`` moves (one word per line, as the block's counters show it); it cannot wait, so its
    sink must take every word when it comes (the testbenches' ``always_ready``)."""

    def __init__(self, block, width: int, seg_bits: int = SEG_BITS):
        self.block, self._width, self._bits = block, width, seg_bits
        super().__init__({"i": In(stream.Signature(seg_bits + RANGE_BITS)), "o": Out(stream.Signature(16)),
                          "log": Out(stream.Signature(16))})

    def elaborate(self, platform):
        m = Module()
        b, bits = self.block, self._bits
        started = Signal()        # the range word taken: the block's clock runs
        m.submodules.block = EnableInserter({"sync": started})(b)
        lo, hi = Signal(10, init=0), Signal(11, init=self._width)
        seg = self.i.payload[:bits]
        is_range = self.i.payload[bits + RANGE_BITS - 1]
        m.d.comb += [b.i.valid.eq(self.i.valid & started & ~is_range), b.i.payload.eq(seg),
                     self.i.ready.eq(is_range | (started & b.i.ready)), b.lo.eq(lo), b.hi.eq(hi)]
        with m.If(self.i.valid & self.i.ready & (is_range | seg[0])):
            m.d.sync += [lo.eq(self.i.payload[bits:bits + 10]), hi.eq(self.i.payload[bits + 10:bits + 21])]
        with m.If(self.i.valid & is_range):
            m.d.sync += started.eq(1)
        m.d.comb += [self.o.valid.eq(b.o.valid & started), self.o.payload.eq(b.o.payload),
                     b.o.ready.eq(self.o.ready & started)]
        seen = Signal(16)
        m.d.comb += [self.log.valid.eq(b.lines != seen), self.log.payload.eq(b.line_cycles)]
        with m.If(self.log.valid & self.log.ready):
            m.d.sync += seen.eq(b.lines)
        return m


def job_stimulus(jb: dict, what: str = "") -> Stimulus:
    """The jobs ``jb`` (``pxp_jobs.job_list`` / ``span_job_list``) as the PXP testbenches' input:
    the first job's range word, then the jobs' words."""
    bits = jb.get("seg_bits", SEG_BITS)
    return Stimulus({"i": [range_word(jb["lo0"], jb["hi0"], bits), *jb["words"]]},
                    what=what or f"{jb['lines']} PXP lines", source=jb)


def _frame(params: dict, seed: int):
    """A random EXPERTS frame at the block's width (square), bit-accurate model, A.J. as built."""
    rng = np.random.default_rng(seed)
    w = params["width"]
    # the paper's scenes; a block built for fewer triangles or a smaller DMM/P bank (a quick test)
    # gets scenes that fit it (at 64 px c50 is up to about 240 triangles and 16 segments a line,
    # experts-solids 37 triangles)
    tris, depth = params.get("tris", 1000), params.get("depth", 256)
    names = (["experts-1000", "experts-tilt-1000", "c100"] if tris >= 1000 and depth >= 64 else
             ["c50", "experts-solids"] if tris >= 256 else ["experts-solids"])
    name = str(rng.choice(names))
    sc = build_scene(name, seed=int(rng.integers(0, 1 << 30)))
    return rng, name, render_frame(run_geometry(sc, w, w, z_bits=16), model="bit", aj=params.get("aj", "none"))


def _lines(rng, width: int, n: int, *, whole: bool = False) -> list[tuple[int, int, int]]:
    """``n`` random PXP lines ``(y, lo, hi)``, the first one (``whole``: every one) the whole line."""
    out = [(int(rng.integers(0, width)), 0, width)]
    for _ in range(n - 1):
        if whole:
            out.append((int(rng.integers(0, width)), 0, width))
            continue
        lo = int(rng.integers(0, width))
        out.append((int(rng.integers(0, width)), lo, int(rng.integers(lo + 1, width + 1))))
    return out


class PxpBench(Testbench):
    """``experts-pxp``: the first line's range word, then one line's segments and ``last`` token
    at a time in (``i``, the range of the next line on the token), the line's pixel words out
    (``o``), as the golden PXP gives them; cycles from the golden cycle model
    (``golden_model/experts/pxp_cycles.py: schedule``).

    ``PxpBench(log=True)`` (the scene runs, ``sim/experts/pxp_sim.py: run_jobs``) also collects
    the adapter's line log (``log``: every line's finish-time counter, never back-pressured),
    expected equal to the cycle model's line cycles."""

    block = "experts-pxp"
    whole_lines = False     # every line the whole width (the range never changes)
    always_ready = ("log",)

    def __init__(self, log: bool = False):
        self.log = log

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        return ("o", "log") if self.log else ("o",)

    def dut(self, params: dict):
        return RangeFromTokens(registry.load(registry.blocks()[self.block])(**params), params["width"])

    def max_segments(self, params: dict) -> int | None:
        """Segments a line may hold (None: any)."""
        return None

    def segments(self, fr, line: tuple[int, int, int]) -> int:
        """Segments line ``(y, lo, hi)`` puts in the block's bank."""
        return len(line_segments(fr, *line, aj=fr.aj))

    def lines(self, params: dict, rng, fr, name: str, seed: int) -> list[tuple[int, int, int]]:
        """The random PXP lines of a stimulus, those the block can hold: a line with more segments
        than ``max_segments`` would stall the block for good (its ``overflow``, by design), so it is
        left out; none left is refused in one line, not run."""
        todo = _lines(rng, params["width"], int(rng.integers(2, 9)), whole=self.whole_lines)
        cap = self.max_segments(params)
        if cap is not None:
            todo = [t for t in todo if self.segments(fr, t) <= cap]
            if not todo:
                raise ValueError(f"{self.block}: no line of {name} at {params['width']} (seed {seed}) "
                                 f"fits {cap} segments; take a larger depth")
        return todo

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng, name, fr = _frame(params, seed)
        jb = job_list(fr, self.lines(params, rng, fr, name, seed))
        return job_stimulus(jb, f"{name} at {params['width']}, {jb['lines']} lines, seed {seed}")

    def words(self, jb: dict) -> dict[str, list[int]]:
        """The golden model's words of every output port."""
        return {"o": jb["pixels"].tolist(), **({"log": jb["cycles"].tolist()} if self.log else {})}

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        jb = stim.source
        # the model's cycle 0 is line 0's first clear cycle, one PXP edge after its first, and the
        # last pixel leaves on the edge after its drain cycle: the PXP's edges up to the last pixel
        # are last_pixel + 2 (as tests/experts/test_experts_pxp_pysim.py); the run's edge 0 takes
        # the range word (the PXP's clock starts after it): + 1
        return Expected(self.words(jb), cycles=int(jb["last_pixel"]) + 3)


class PxpSpanBench(PxpBench):
    """``experts-pxp-span`` (the span PXP): the first line's range word, then per line the
    DMM/P words the SLP writes -- the line's whole ASL, this PXP's block boundary bucket list, the
    ``last`` token with the block leading segment pointer (and the next line's range for the
    adapter) -- in (``i``), the range's pixel words out (``o``), as the golden bit model gives
    them; cycles from ``golden_model/experts/span_cycles.py: schedule`` (last pixel's edge + 1,
    + 1 for the range word); ``log=True``: the line log too (:class:`PxpBench`)."""

    block = "experts-pxp-span"

    def dut(self, params: dict):
        return RangeFromTokens(registry.load(registry.blocks()[self.block])(**params), params["width"], SPAN_BITS)

    pxp = "span"

    def max_segments(self, params: dict) -> int | None:
        return params["depth"]          # ASBs (and bucket entries, never more) per DMM/P bank

    def segments(self, fr, line: tuple[int, int, int]) -> int:
        from rasterhw.golden_model.experts.span_cycles import line_asl
        return len(line_asl(fr, line[0])[0])   # the line's whole ASL goes to the bank

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng, name, fr = _frame(params, seed)
        jb = span_job_list(fr, self.lines(params, rng, fr, name, seed), pxp=self.pxp)
        if params.get("datapath", "ours") == "paper":      # one multiplier: span_cycles.paper_jobs
            from rasterhw.golden_model.experts.span_cycles import paper_jobs
            jb = paper_jobs(jb)
        return job_stimulus(jb, f"{name} at {params['width']}, {jb['lines']} lines, seed {seed}")

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        jb = stim.source
        return Expected(self.words(jb), cycles=int(jb["last_pixel"]) + 2)


class PxpCoherentBench(PxpSpanBench):
    """``experts-pxp-coherent`` (ours: span cull once per segment, depth search only where the
    visible segment can change): :class:`PxpSpanBench`'s words and pixels, cycles from
    ``golden_model/experts/coherent.py`` through ``span_cycles.schedule``."""

    block = "experts-pxp-coherent"
    pxp = "coherent"


class PxpUnitBench(PxpBench):
    """``experts-pxp-unit`` (DMM/P + PXP): the PXP's stimulus and pixels, every line the whole
    width (the range inputs reach the PXP directly while the DMM/P holds lines back, so a range
    riding on the tokens would arrive early); the DMM/P in front of the PXP delays every line, so
    the golden PXP cycle model does not apply (no cycle check)."""

    block = "experts-pxp-unit"
    whole_lines = True

    def max_segments(self, params: dict) -> int | None:
        return params["depth"] - 1      # the DMM/P bank holds the segments and the last token

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        return Expected({"o": stim.source["pixels"].tolist()})


class DmmBench(Testbench):
    """``experts-dmm``: lines of segment words, each ended by its ``last`` token, in (``i``) and
    the same words out (``o``), a line at a time (the DMM/P changes nothing, it only buffers).
    A line with more segments than a bank holds keeps its first ``depth - 1``."""

    block = "experts-dmm"

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng, name, fr = _frame({"width": 64}, seed)
        jb = job_list(fr, _lines(rng, 64, int(rng.integers(2, 9))))
        mask, words = (1 << SEG_BITS) - 1, []
        for segs in jb["segments"]:
            line = [w & mask for w in jb["words"][len(words):len(words) + len(segs) + 1]]
            words += line
        out, line = [], []
        for w in words:
            if w & 1:   # the last token ends a line
                out += line[:params["depth"] - 1] + [w]
                line = []
            else:
                line.append(w)
        return Stimulus({"i": out}, what=f"{name} segments, {jb['lines']} lines, seed {seed}")

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        return Expected({"o": list(stim.words["i"])})


def slp_words(fr, band: tuple[int, int], bounds, *, guard: int) -> dict:
    """``experts-slp`` stimulus and expectation for one band of a frame: the input words (band,
    range bounds, PL triangles, go), the output words and cycles of
    ``golden_model/experts/slp_cycles.py: band_run`` (its ``line_cycles`` and ``asl`` too)."""
    from rasterhw.golden_model.experts.slp_cycles import band_run, tri_words
    from rasterhw.hdl.experts.slp import IN_KIND, slp_in_layout, slp_out_layout
    from rasterhw.hdl.pack import pack
    li, lo = slp_in_layout(), slp_out_layout()
    tws = tri_words(fr.setup)
    br = band_run(tws, band, bounds, width=fr.width, guard=guard, extra=fr.setup.fmt.datapath.acc_extra)
    words = [pack(li, {"kind": IN_KIND["band"], "r0": band[0], "r1": band[1]})]
    words += [pack(li, {"kind": IN_KIND["bound"], "xa": int(v)}) for v in bounds]
    words += [pack(li, {"kind": IN_KIND["tri"], **tw}) for tw in tws] + [pack(li, {"kind": IN_KIND["go"]})]
    out = [pack(lo, {"kind": k, "p": p, "pos": pos, "t": t, "y": y, "asb": a or {}})
           for k, p, pos, t, y, a in br["words"]]
    return {"in": words, "out": out, **br, "tris": len(tws)}


def setup_words(pls: list[dict], band: tuple[int, int], height: int, extra: int = ACC_EXTRA) -> dict:
    """``experts-slp-setup`` stimulus and expectation for one band: the band word and every PL
    triangle (``golden_model/experts/slp_setup.py: pl_words``) in, the triangle words the list work
    takes out, each on the edge ``band_setup``'s cycles put it (``stamps``: the band word's cycle,
    then each triangle's cycles)."""
    from rasterhw.golden_model.experts.slp_setup import band_setup
    from rasterhw.hdl.experts.slp import IN_KIND, slp_in_layout
    from rasterhw.hdl.experts.slp_setup import PL_KIND, pl_layout
    from rasterhw.hdl.pack import pack
    li, lo = pl_layout(), slp_in_layout()
    bs = band_setup(pls, band, height, extra)
    words = [pack(li, {"kind": PL_KIND["band"], "r0": band[0], "r1": band[1]})]
    words += [pack(li, {"kind": PL_KIND["tri"], **pl}) for pl in pls]
    stamps, t = [], 1
    for c in bs["tri_cycles"]:
        t += c
        stamps.append(t - 1)
    return {"in": words, "out": [pack(lo, {"kind": IN_KIND["tri"], **w}) for w in bs["words"]],
            "stamps": stamps, **bs}


class SlpSetupBench(Testbench):
    """``experts-slp-setup`` (the SLP's set-up: multiplier and reciprocal ROM): one band of a random
    frame -- the band word, then every PL triangle -- in (``i``); every triangle's word for the list
    work out (``o``), as ``golden_model/experts/slp_setup.py`` gives them (equal to
    ``slp_cycles.tri_words`` in the band); cycles: the last word's edge + 1 = the band word's cycle
    and every triangle's."""

    block = "experts-slp-setup"

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        from rasterhw.golden_model.experts.slp_setup import pl_words
        H = params["height"]
        rng, name, fr = _frame({"width": H, "tris": 999}, seed)
        n = int(rng.integers(1, H + 1))
        y0 = int(rng.integers(0, H - n + 1))
        sw = setup_words(pl_words(fr.setup), (y0, y0 + n), H)
        return Stimulus({"i": sw["in"]}, what=f"{name} at {H}, band {y0}..{y0 + n}, seed {seed}", source=sw)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        return Expected({"o": stim.source["out"]}, cycles=1 + int(stim.source["cycles"]))


class SlpBench(Testbench):
    """``experts-slp``: one band of a random frame -- band, PXP range bounds, the PL triangles with
    their set-up, go -- in (``i``); per line the ASL words with the leading pointers and bucket
    entries as the walk finds them, then the end-of-line word, out (``o``), as
    ``golden_model/experts/slp_cycles.py`` gives them (from ``slp_run``'s sorts, run); cycles: the
    last output's edge + 1 = every term of ``band_run`` summed."""

    block = "experts-slp"

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        rng, name, fr = _frame({"width": params["width"], "tris": params["tris"],
                                "aj": "c" if params["guard"] else "none"}, seed)
        H = fr.height
        n = int(rng.integers(1, min(params["lines"], H) + 1))
        y0 = int(rng.integers(0, H - n + 1))
        from rasterhw.golden_model.experts.model import equal_bounds
        pn = int(rng.integers(1, 5))
        sw = slp_words(fr, (y0, y0 + n), equal_bounds(params["width"], pn), guard=params["guard"])
        if sw["tris"] > params["tris"]:
            raise ValueError(f"{name}: {sw['tris']} triangles, the SLP holds {params['tris']}")
        return Stimulus({"i": sw["in"]}, what=f"{name} at {params['width']}, band {y0}..{y0 + n}, {pn} ranges, "
                        f"seed {seed}", source=sw)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        return Expected({"o": stim.source["out"]}, cycles=int(stim.source["cycles"]))


class GroupBench(Testbench):
    """``experts-group`` (one SLP, its DMM/P writers and Pn span PXPs clocked together): one band of a
    random frame in (``i``, as :class:`SlpBench`), each PXP's pixels of the band out (``o[k]``), as
    the golden bit model gives them. No cycle model (the SLP and the PXPs pace each other through
    the DMM/P banks): the engines' stamps are compared with each other only."""

    block = "experts-group"

    def outputs_of(self, params: dict) -> tuple[str, ...]:
        return tuple(f"o[{k}]" for k in range(params["pn"]))

    def stimulus(self, params: dict, seed: int) -> Stimulus:
        from rasterhw.golden_model.experts.model import equal_bounds
        rng, name, fr = _frame({"width": params["width"], "tris": params["tris"], "aj": params["aj"]}, seed)
        H = fr.height
        n = int(rng.integers(1, min(params["lines"], H) + 1))
        y0 = int(rng.integers(0, H - n + 1))
        b = equal_bounds(params["width"], params["pn"])
        sw = slp_words(fr, (y0, y0 + n), b, guard=1 if params["aj"] == "c" else 0)
        # what the group cannot hold sets its overflow and gives wrong pixels: refused, not run
        if sw["tris"] > params["tris"]:
            raise ValueError(f"{name}: {sw['tris']} triangles, the SLP holds {params['tris']}")
        from rasterhw.golden_model.experts.span_cycles import line_asl
        most = max(len(line_asl(fr, y)[0]) for y in range(y0, y0 + n))
        if most > min(params["asl"], params["depth"]):
            raise ValueError(f"{name}: a line of {most} segments, the SLP's ASL holds {params['asl']} and a "
                             f"DMM/P bank {params['depth']}")
        from rasterhw.golden_model.experts.pxp import pixel_words
        pix = pixel_words(fr.setup, fr.fields).reshape(H, fr.width)
        out = {f"o[{k}]": [int(v) for y in range(y0, y0 + n) for v in pix[y, int(b[k]):int(b[k + 1])]]
               for k in range(params["pn"])}
        return Stimulus({"i": sw["in"]}, what=f"{name} at {params['width']}, band {y0}..{y0 + n}, "
                        f"{params['pn']} PXPs, seed {seed}", source=out)

    def expect(self, params: dict, stim: Stimulus) -> Expected:
        return Expected(dict(stim.source))
