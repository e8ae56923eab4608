"""What the plain-Verilator engine needs of a bench top's ports without elaborating the block:
each stream port's plusarg stem (:func:`tag`) and payload width, and the testbench's status values
(names and widths), kept beside the generated Verilog in the build cache (:func:`bench_ports`).
A warm run (Verilog cached, model built) so never constructs the block, nor imports Amaranth:
about 0.3 CPU-s of a ``rasterhw sim`` command."""

from __future__ import annotations

import hashlib
import json

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cachefile import read_entry, write_entry
from rasterhw.sim.paths import BUILD_ROOT
from rasterhw.sim.testbench import Testbench, port_of

__all__ = ["GAP_BITS", "bench_ports", "payload_of", "ports_of", "tag", "unpack"]

GAP_BITS = 8          # idle clocks before a word: 0..255


def tag(path: str) -> str:
    """Port path -> plusarg stem: ``o_merge[3]`` -> ``o_merge_3``."""
    return path.replace("[", "_").replace("]", "").replace(".", "_")


def payload_of(port):
    """A stream port's payload as a plain Amaranth value (a view's underlying value)."""
    p = port.payload
    return p.as_value() if hasattr(p, "as_value") else p


def ports_of(tb: Testbench, params: dict, dut) -> dict:
    """``{"widths": {port: payload bits} of every stream port, "status": [[name, bits], ...]}`` of
    ``tb``'s block ``dut`` (its status values checked: 64 bits together at most)."""
    st = tb.status(dut, params)
    if sum(len(v) for v in st.values()) > 64:
        raise RasterhwError(f"{tb.block}: status values wider than 64 bits together")
    names = (*tb.inputs_of(params), *tb.outputs_of(params))
    return {"widths": {n: len(payload_of(port_of(dut, n))) for n in names},
            "status": [[k, len(v)] for k, v in st.items()]}


def bench_ports(tb: Testbench, params: dict, key: str, text: str) -> dict:
    """:func:`ports_of` of the bench top whose cache key (``verilator.bench_design``: parameters,
    memory depths, the digest of every source of the bench) is ``key`` and whose Verilog is
    ``text``, from ``build/verilog/<block>-ports-<digest>.json`` (digest of both), or found once by
    constructing the block (not elaborated) and written there."""
    digest = hashlib.sha1((key + "\0" + text).encode()).hexdigest()[:16]
    path = BUILD_ROOT / "verilog" / f"{tb.block}-ports-{digest}.json"
    got = read_entry(path, what=f"the port widths of {tb.block}'s bench")
    if got is not None:
        return json.loads(got)
    found = ports_of(tb, params, tb.dut(params))
    try:
        write_entry(path, json.dumps(found, sort_keys=True).encode(), root=BUILD_ROOT)
    except OSError:
        pass   # a read-only cache: found again next time
    return found


def unpack(status: list, word: int) -> dict[str, int]:
    """A packed status word -> ``{name: value}`` (``status``: ``[[name, bits], ...]`` in packing order)."""
    out, at = {}, 0
    for name, bits in status:
        out[name] = (word >> at) & ((1 << bits) - 1)
        at += bits
    return out
