"""``rasterhw sim experts``: a whole frame through the SLP HDL and then the span PXP HDL.

Every band's set-up runs in ``experts-slp-setup`` (the bands back to back through one instance: the
band word, then every PL triangle, ``golden_model/experts/slp_setup.py: pl_words``): the triangle
words for the list work (sorted vertices, edge increments, eq. (3), the A.J. slopes, with the
multiplier and the reciprocal ROM) compared word for word with ``slp_setup.band_setup`` (which equals
``slp_cycles.tri_words`` in the band) and cycle for cycle (stamps). Those words -- the HDL's -- are
the PL triangles every band's list work takes. Every band's SLP list work runs in ``experts-slp`` (the bands back to back through one instance: the
SLPs are identical and independent, "ホスト計算機はすべての SLP に同一の PL を送出するだけ"): band,
range bounds and the PL in; per line its ASL order, block leading pointers and bucket lists out,
compared word for word and end-of-line by end-of-line (cycle stamps) with
``golden_model/experts/slp_cycles.py``. Those words -- the HDL's, not the golden SLP's -- then make
every PXP's DMM/P words (the line's ASL in the SLP's order, that PXP's bucket list and leading
pointer; each ASB's fields from the golden records), which run through ``experts-pxp-span`` as ``rasterhw sim pxp`` runs them: pixels against the
golden bit model, every line's finish-time counter against ``span_cycles``.

Frame times: an SLP's is its band's set-up cycles plus its list-work cycles (band start + its
lines), both as the HDL took them (the two units are one processor's two phases, run one after
the other; the sum is of two HDL counts, each checked against its cycle model), a PXP's its own lines back to
back (``span_cycles.schedule``); the clock for 30 frames/s is the busiest one's cycles x 30, for
SLPs and PXPs side by side. The SLP and PXP runs are chained, not clocked together: the DMM/P
between them would overlap them in the machine.

``datapath``: ``ours`` (today's HDL, the default) or ``paper`` (16-bit words, one multiplier a
processor: ``formats.DATAPATHS``). Both report the golden bit model's error against the float model
at their widths (``accuracy.float_error``, ``accuracy_source`` golden). ``paper`` runs the frame's
golden bit model at the paper's widths and the SLP HDL with 16-bit edge increments and accumulators
(``acc_extra`` 0); the rest of the HDL is ours' (``HDL_WIDEST_BITS``, ``HDL_MULTIPLIERS``: what the
result's ``datapath_bits`` and ``multipliers`` say; the contract's are ``contract_*``).
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.model import equal_bounds, render_frame
from rasterhw.sim.experts.pxp_sim import ENGINES, hdl_image, jobs, run_jobs

__all__ = ["simulate_frame", "decode_slp"]


def decode_slp(words: list[int]) -> list[tuple]:
    """``experts-slp`` output words -> ``(kind, p, pos, t, y, ASB dict)`` (signed fields sign-extended)."""
    from amaranth import Shape
    from rasterhw.hdl.experts.slp import slp_out_layout
    lay = slp_out_layout()
    top = {n: (f.offset, Shape.cast(f.shape).width) for n, f in lay}
    sub = [(n, top["asb"][0] + f.offset, Shape.cast(f.shape)) for n, f in lay.members["asb"]]

    def field(v, off, w, signed=False):
        x = (v >> off) & ((1 << w) - 1)
        return x - (1 << w) if signed and x >> (w - 1) else x
    out = []
    for v in words:
        head = tuple(field(v, top[n][0], top[n][1]) for n in ("kind", "p", "pos", "t", "y"))
        out.append((*head, {n: field(v, off, sh.width, sh.signed) for n, off, sh in sub}))
    return out


def simulate_frame(scene, width: int, height: int, *, engine: str = "verilator", progress: bool = False,
                   sn: int | None = 8, pn: int | None = 8, aj: str | None = "c", path: str | None = "chained",
                   datapath: str | None = "ours") -> dict:
    """Registry sim block ``experts``: the frame's SLP bands and PXP lines in HDL, against golden.

    ``path="group"``: every band instead through ``experts-group`` (the SLP, its DMM/P writers and
    Pn span PXPs clocked together, one run per band): pixels against golden, and the band's cycles
    as measured (no cycle model: SLP and PXPs pace each other), ``group_cycles`` the slowest band."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.sim.engines import run
    from rasterhw.sim.experts.testbench import SlpBench, slp_words
    from rasterhw.sim.testbench import Stimulus
    if engine not in ENGINES:
        raise RasterhwError(f"experts: sim experts engine must be one of {', '.join(ENGINES)}, not {engine!r}")
    sn = 8 if sn is None else sn
    pn = 8 if pn is None else pn
    aj = "c" if aj is None else aj
    if aj not in ("none", "c"):
        raise RasterhwError(f"experts: sim experts aj must be none or c, not {aj!r}")
    if not (1 <= sn <= height and 1 <= pn <= min(width, 63)):
        raise RasterhwError(f"experts: sn must be 1..{height} and pn 1..{min(width, 63)}")
    path = "chained" if path is None else path
    if path not in ("chained", "group"):
        raise RasterhwError(f"experts: sim experts path must be chained or group, not {path!r}")
    from rasterhw.golden_model.experts.formats import DATAPATHS
    datapath = "ours" if datapath is None else datapath
    if datapath not in DATAPATHS:
        raise RasterhwError(f"experts: sim experts datapath must be one of {', '.join(DATAPATHS)}, not {datapath!r}")
    if datapath == "paper" and path != "chained":
        raise RasterhwError("experts: sim experts --datapath paper: experts-group has no 16-bit configuration; "
                            "leave --path at chained")
    t0 = time.perf_counter()
    tris = run_geometry(scene, width, height, z_bits=16)
    acc = _accuracy(tris, datapath, aj)
    from rasterhw.golden_model.experts.formats import Formats
    ex = DATAPATHS[datapath].acc_extra
    fr = render_frame(tris, model="bit", aj=aj, fmt=Formats(datapath=DATAPATHS[datapath]))
    if path == "group":
        return {**_group_frame(fr, engine, sn, pn, aj, t0, progress), **acc}
    guard = 1 if aj == "c" else 0
    bands = equal_bounds(height, sn)
    bounds = equal_bounds(width, pn)
    # the list work's golden side first: it refuses a PL the SLP cannot hold before any HDL runs
    sws = [slp_words(fr, (int(bands[s]), int(bands[s + 1])), bounds, guard=guard) for s in range(sn)]
    # ---- the SLPs' set-up: every band back to back through one experts-slp-setup (band word, the PL)
    from rasterhw.golden_model.experts.slp_setup import pl_words
    from rasterhw.sim.experts.testbench import SlpSetupBench, setup_words
    pls = pl_words(fr.setup)
    sus = [setup_words(pls, (int(bands[s]), int(bands[s + 1])), height, ex) for s in range(sn)]
    stb = SlpSetupBench()
    su_in = [w for su in sus for w in su["in"]]
    su_want = [w for su in sus for w in su["out"]]
    su_stamps, t = [], 0
    for su in sus:
        su_stamps += [t + st for st in su["stamps"]]
        t += 1 + su["cycles"]
    n_pl = len(pls)
    if n_pl:
        if progress:
            print(f"experts: {sn} SLP set-ups, {len(su_in)} words in, {t:,} set-up cycles expected", file=sys.stderr)
        sgot = run(stb, stb.params(height=height, acc_extra=ex), Stimulus({"i": su_in}), engine=engine,
                   expect_words={"o": len(su_want)}, max_cycles=2 * t + 10000)
        su_have, su_got_stamps, su_run_s, su_sim = sgot.words["o"], list(sgot.stamps["o"]), sgot.run_s, int(sgot.cycles)
    else:       # an empty PL: no set-up work, nothing to run (each band word alone, 1 cycle)
        su_have, su_got_stamps, su_run_s, su_sim = [], [], 0.0, 0
    su_mism = sum(a != b for a, b in zip(su_want, su_have, strict=False)) + abs(len(su_want) - len(su_have))
    su_cyc_mism = (sum(a != b for a, b in zip(su_stamps, su_got_stamps, strict=False))
                   + abs(len(su_stamps) - len(su_got_stamps)))
    # each band's set-up cycles as the HDL took them: from the stamp of its last word to the next's
    if n_pl and len(su_got_stamps) == sn * n_pl:
        last = [int(su_got_stamps[(s + 1) * n_pl - 1]) for s in range(sn)]
        setup_band = [last[0] + 1] + [last[s] - last[s - 1] for s in range(1, sn)]
    else:       # an empty PL, or a failed run (its mismatches say so): the cycle model's
        setup_band = [1 + su["cycles"] for su in sus]
    # ---- the SLPs' list work: every band back to back through one experts-slp, on the set-up HDL's words
    nb = 1 + len(bounds)
    for s, sw in enumerate(sws):
        hw = su_have[s * n_pl:(s + 1) * n_pl]
        if len(hw) == n_pl:
            sw["in"] = sw["in"][:nb] + list(hw) + sw["in"][nb + n_pl:]
    tb = SlpBench()
    p = tb.params(width=width, tris=max(2, min(4095, max(sw["tris"] for sw in sws))),
                  lines=max(1, int(np.diff(bands).max())), asl=256, guard=guard, acc_extra=ex)
    words_in = [w for sw in sws for w in sw["in"]]
    want = [w for sw in sws for w in sw["out"]]
    total = sum(sw["cycles"] for sw in sws)
    if progress:
        print(f"experts: {sn} SLP bands, {len(words_in)} words in, {len(want)} out, {total:,} SLP cycles expected",
              file=sys.stderr)
    got = run(tb, p, Stimulus({"i": words_in}), engine=engine, expect_words={"o": len(want)},
              max_cycles=2 * total + 10000)
    have = got.words["o"]
    slp_mism = sum(a != b for a, b in zip(want, have, strict=False)) + abs(len(want) - len(have))
    # every end-of-line word on the golden cycle: band start, then its lines, band after band
    eol_want, t = [], 0
    band_end = []
    for sw in sws:
        t += sw["start_cycles"]
        for c in sw["line_cycles"]:
            t += c
            eol_want.append(t - 1)
        band_end.append(len(eol_want) - 1)
    dec = decode_slp(have)
    eol_got = [st for st, w in zip(got.stamps["o"], dec, strict=False) if w[0] == 3]
    slp_cyc_mism = sum(a != b for a, b in zip(eol_want, eol_got, strict=False)) + abs(len(eol_want) - len(eol_got))
    # each band's list-work cycles as the HDL took them: from one band's last end-of-line word to the next's
    ends = [int(eol_got[k]) if k < len(eol_got) else 0 for k in band_end]
    list_band = [ends[0] + 1] + [ends[s] - ends[s - 1] for s in range(1, sn)]
    # ---- the HDL SLP's lists -> every PXP's DMM/P words
    lists: dict = {}
    line: dict = {"asl": [], "lead": {}, "bk": {}}
    for kind, q, pos, _t, y, a in dec:
        if kind == 0:
            line["asl"].append(a)
        elif kind == 1:
            line["lead"][q] = pos
        elif kind == 2:
            line["bk"].setdefault(q, []).append(pos)
        else:
            for r in range(pn):
                lists[(y, int(bounds[r]), int(bounds[r + 1]))] = (line["asl"], line["lead"].get(r, -1),
                                                                  line["bk"].get(r, []))
            line = {"asl": [], "lead": {}, "bk": {}}
    if len(lists) != height * pn:
        raise RasterhwError(f"experts: the SLP HDL gave lists for {len(lists) // max(pn, 1)} of {height} lines")
    jb = jobs(fr, sn, pn, pxp="span", slp=lists)
    res = run_jobs(jb, width=width, engine=engine)
    px = res["pixels"]
    n = min(px.size, jb["pixels"].size)
    mism = int(np.count_nonzero(px[:n] != jb["pixels"][:n])) + abs(px.size - jb["pixels"].size)
    cyc = res["cycles"][:jb["lines"]]
    pxp_cyc_mism = int(np.count_nonzero(cyc != jb["cycles"][:cyc.size])) + (jb["lines"] - cyc.size)
    # one SLP does its band's set-up, then its list work: its frame is the two, the busiest band's
    slp_band = [a + b for a, b in zip(setup_band, list_band, strict=True)]
    busiest = int(np.argmax(slp_band))
    slp_frame = slp_band[busiest]
    cycles = su_sim + int(got.cycles) + int(res["sim_cycles"])
    run_s = su_run_s + got.run_s + res["run_s"]
    pxp_frame = int(jb["pxp_frame_cycles"].max())
    return {"engine": engine, "cycles": cycles, "clock_hz": None,
            "cycles_per_s": round(cycles / run_s, 1) if run_s > 0 else None, "pixels_compared": int(n), "mismatches": mism + slp_mism + su_mism,
            "pixel_mismatches": mism, "slp_word_mismatches": slp_mism, "slp_words": len(want),
            "slp_setup_word_mismatches": su_mism, "slp_setup_words": len(su_want),
            "cycle_mismatches": slp_cyc_mism + pxp_cyc_mism + su_cyc_mism,
            "slp_cycle_mismatches": slp_cyc_mism, "pxp_cycle_mismatches": pxp_cyc_mism,
            "slp_setup_cycle_mismatches": su_cyc_mism,
            # the busiest SLP's band: set-up (experts-slp-setup) + list work (experts-slp), HDL cycles
            "slp_cycles": slp_frame, "slp_setup_cycles": int(setup_band[busiest]),
            "slp_list_cycles": int(list_band[busiest]), "slp_busiest_band": busiest,
            "slp_setup_cycles_per_band": [int(v) for v in setup_band],
            "slp_list_cycles_per_band": [int(v) for v in list_band], "pxp_cycles": pxp_frame,
            "slp_clock_for_30fps_hz": slp_frame * 30, "pxp_clock_for_30fps_hz": pxp_frame * 30,
            "bottleneck": "SLP" if slp_frame > pxp_frame else "PXP",
            "sn": sn, "pn": pn, "aj": aj, "pxp": "span", "wall_s": round(time.perf_counter() - t0, 3),
            "slp_run_s": round(got.run_s, 3), "slp_setup_run_s": round(su_run_s, 3), "pxp_run_s": round(res["run_s"], 3),
            # SLPs and PXPs work side by side: the machine's frame is the slower of the two
            "frame_cycles": max(slp_frame, pxp_frame), **acc, "frame_rgb": hdl_image(fr, px)}


#: what the HDL of the chained frame has, at either datapath: its widest register (the set-up's 40 x 20
#: multiplier, the PXPs' running z and i) and its multipliers (set-up 1; list work 3, x of a triangle's
#: three edges at its entry; span PXP 3, z at a span's two ends and i at its start). ``paper`` makes the
#: SLP's edge increments and accumulators 16 bits (acc_extra 0); the rest is not yet at 16 bits.
HDL_WIDEST_BITS = 40
HDL_MULTIPLIERS = {"slp_setup": 1, "slp_list": 3, "pxp_span": 3}


def _accuracy(tris, datapath: str, aj: str) -> dict:
    """The datapath's contract, what the HDL has, and the golden bit model's error against float
    (``accuracy_source`` golden). ``datapath_bits`` and ``multipliers`` are the HDL's (the widest
    register, the most multipliers in one processor); ``contract_*`` the golden contract's."""
    from rasterhw.golden_model.experts.accuracy import float_error
    e = float_error(tris, datapath, aj=aj)
    return {"datapath": e["datapath"], "datapath_label": e["label"], "datapath_bits": HDL_WIDEST_BITS,
            "multipliers": max(HDL_MULTIPLIERS.values()), "hdl_multipliers": HDL_MULTIPLIERS,
            "contract_datapath_bits": e["datapath_bits"], "contract_multipliers": e["multipliers"],
            "hdl_16_bit": "SLP edge increments and accumulators" if datapath == "paper" else "none",
            "max_abs_error": e["max_abs_error"],
            "pixels_differing_from_float": e["pixels_differing_from_float"], "psnr_db": round(e["psnr_db"], 3),
            "visible_differing_from_float": e["visible_differing"],
            "pixels_differing_from_ours": e["pixels_differing_from_ours"], "accuracy_source": "golden"}


def _group_frame(fr, engine: str, sn: int, pn: int, aj: str, t0: float, progress: bool) -> dict:
    """Every band through ``experts-group``; pixels against golden, cycles measured per band."""
    from rasterhw.golden_model.experts.pxp import pixel_words
    from rasterhw.sim.engines import run
    from rasterhw.sim.experts.testbench import GroupBench, slp_words
    from rasterhw.sim.testbench import Stimulus, compare
    W, H = fr.width, fr.height
    bands = equal_bounds(H, sn)
    b = equal_bounds(W, pn)
    pix = pixel_words(fr.setup, fr.fields).reshape(H, W)
    tb = GroupBench()
    sws = [slp_words(fr, (int(bands[s]), int(bands[s + 1])), b, guard=1 if aj == "c" else 0) for s in range(sn)]
    p = tb.params(width=W, pn=pn, aj=aj, tris=max(2, min(4095, max(sw["tris"] for sw in sws))),
                  lines=max(1, int(np.diff(bands).max())), asl=256, depth=256)
    mism = n = 0
    band_cycles, run_s = [], 0.0
    for s in range(sn):
        y0, y1 = int(bands[s]), int(bands[s + 1])
        want = {f"o[{k}]": [int(v) for y in range(y0, y1) for v in pix[y, int(b[k]):int(b[k + 1])]] for k in range(pn)}
        if progress:
            import sys
            print(f"experts: band {s} through experts-group", file=sys.stderr)
        got = run(tb, p, Stimulus({"i": sws[s]["in"]}), engine=engine,
                  expect_words={k: len(v) for k, v in want.items()}, max_cycles=20 * sws[s]["cycles"] + 100000)
        c = compare(_expected(want), got)
        mism += c["mismatches"]
        n += sum(len(v) for v in want.values())
        band_cycles.append(got.cycles)
        run_s += got.run_s
    worst = max(band_cycles)
    slp_model = max(sw["cycles"] for sw in sws)
    return {"engine": engine, "path": "group", "cycles": int(sum(band_cycles)), "clock_hz": None,
            "cycles_per_s": round(sum(band_cycles) / run_s, 1) if run_s > 0 else None,
            "pixels_compared": n, "mismatches": mism, "group_cycles": int(worst),
            "group_cycles_per_band": [int(c) for c in band_cycles],
            "group_clock_for_30fps_hz": int(worst) * 30, "slp_cycles_alone": slp_model,
            "sn": sn, "pn": pn, "aj": aj, "wall_s": round(time.perf_counter() - t0, 3)}


def _expected(words):
    from rasterhw.sim.testbench import Expected
    return Expected(words)
