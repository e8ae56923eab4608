# amaranth: UnusedElaboratable=no
"""Verilog generation for the HDL blocks the machines register (``Machine.blocks``).

A block is a factory taking keyword parameters and returning a ``wiring.Component``; a
component that instantiates hand-written Verilog returns that source from its
``extra_verilog()`` method, and it is appended to the generated text.
"""

from __future__ import annotations

import gc
import inspect
import re
import warnings
from collections.abc import Callable
from functools import cache
from typing import TYPE_CHECKING

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.registry import blocks, load

if TYPE_CHECKING:
    from amaranth.lib import wiring

__all__ = ["block_names", "canonical_port_lists", "generate_verilog", "make_block", "merge_identical_modules",
           "parse_params"]


def block_names() -> list[str]:
    """Every registered block, sorted (``rasterhw verilog --list``)."""
    return sorted(blocks())


def make_block(name: str, **params) -> wiring.Component:
    """Build the registered block ``name`` with ``params``; bad names/params raise ``RasterhwError``."""
    refs = blocks()
    if name not in refs:
        raise RasterhwError(f"unknown block {name!r}; known: {', '.join(sorted(refs))}")
    factory = load(refs[name])
    sig = inspect.signature(factory)
    unknown = [k for k in params if k not in sig.parameters]
    if unknown:
        raise RasterhwError(f"block {name!r} has no parameter {unknown[0]!r}")
    return _quietly(lambda: factory(**params), name)


def _quietly(build, name: str):
    """``build()``; a ValueError/TypeError becomes a one-line RasterhwError, with no Amaranth
    warnings after it: a constructor or ``elaborate`` that raised leaves half-built
    sub-components behind, and Amaranth warns about each (UnusedElaboratable) when it is
    collected -- so they are collected here, with that warning ignored."""
    from amaranth.hdl import UnusedElaboratable  # here: the text functions below need no Amaranth

    msg = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnusedElaboratable)
        try:
            return build()
        except RasterhwError as e:
            msg = str(e)
        except (ValueError, TypeError, OverflowError) as e:   # Overflow: a parameter too big for a C size
            msg = f"block {name!r}: {e}"
        gc.collect()
    raise RasterhwError(msg)


def _module_name(name: str) -> str:
    return name.replace("-", "_")


_MODULE_HEADER = re.compile(r"^module (\S+)(\s*)\(([^;]*?)\);", re.MULTILINE | re.DOTALL)


def canonical_port_lists(text: str) -> str:
    """Every ``module NAME(ports);`` header with its port names sorted, on one line.

    Amaranth orders a module's ports partly by iterating a set of domain names, so the order
    (and nothing else: every port is declared by name below the header and every instance is
    connected by name) changes with Python's string-hash seed from one process to the next. The
    caches of generated Verilog, simulator builds, synthesis and place-and-route are keyed on
    the text, so the text must not depend on the process."""
    def fix(m: re.Match) -> str:
        # (an escaped name such as ``\\top.sub`` ends at the white space kept before the list,
        # and so does an escaped port name: it keeps a space before the comma that follows it)
        ports = sorted(p.strip() for p in m.group(3).replace("\n", " ").split(",") if p.strip())
        return f"module {m.group(1)}{m.group(2)}(" + ", ".join(p + " " if p.startswith("\\") else p
                                                              for p in ports) + ");"
    return yosys_init_renamed(_MODULE_HEADER.sub(fix, text))


# Yosys's Verilog backend gives every module with a combinational ``always`` a register that only
# starts those blocks at time 0: ``reg \$auto$verilog_backend.cc:2355:dump_module$5 = 0;``. The
# ``:`` in that name stops GTKWave's VCD reader ("$VAR parse error", issue 53), so every text
# this module writes names it ``_yosys_init_2355_5``: a plain identifier, and one Verilator leaves
# out of traces (it traces no name that starts with ``_`` unless asked, ``--trace-underscore``).
_YOSYS_INIT = re.compile(r"\\\$auto\$verilog_backend\.cc:(\d+):dump_module\$(\d+)(?=\s)")
_YOSYS_INIT_RENAMED = re.compile(r"\b_yosys_init_(\d+)_(\d+)\b")


def yosys_init_renamed(text: str) -> str:
    """``text`` with Yosys's time-0 trigger registers renamed (see above); a one-to-one renaming
    of names local to their module, so the circuit is the same."""
    return _YOSYS_INIT.sub(r"_yosys_init_\1_\2", text)


def yosys_init_restored(text: str) -> str:
    """The inverse of :func:`yosys_init_renamed`: the names Yosys wrote. Cache keys made before
    the renaming (synthesis, place and route: ``sim/flow/synth.py: stable_text``) stay valid."""
    return _YOSYS_INIT_RENAMED.sub(r"\\$auto$verilog_backend.cc:\1:dump_module$\2", text)


_MODULE_START = re.compile(r"^module\s+(\\\S+|[A-Za-z_][\w$]*)")
# an instance line: ``  MODULE  NAME (`` or ``  MODULE #(`` (yosys writes one per line)
_INSTANCE = re.compile(r"^(\s+)(\\\S+|[A-Za-z_][\w$]*)(?=\s+(?:#|\\\S+\s+\(|[A-Za-z_][\w$]*\s*\())")
# yosys-internal names (``\$auto$verilog_backend.cc:2355:dump_module$5``, ``\$12``): local to
# their module, numbered by counters global to the file
_INTERNAL = re.compile(r"\\\$\S+|\b_yosys_init_\d+_\d+\b")


def merge_identical_modules(text: str, *, no_inline: Callable[[str, int, int], bool] | None = None) -> str:
    """``text`` with every module that is identical to an earlier one removed and its instances
    pointed at the earlier one (the first in the file keeps its name).

    Amaranth writes one Verilog module per *instance* (``\\zbm_unit.chip3.loop.pp5`` ...), so a
    block with 8 copies of a sub-block has 8 copies of its text: the simulators compile each
    (Verilator inlines every single-instance module, so the C++ has 8 copies of the same code).
    Two modules are the same here when their text is equal after (1) instantiated module names are
    replaced by their representatives and (2) yosys's internal names (``\\$...``: local wires and
    the per-module ``$auto$...$N`` register, numbered by a counter over the whole file) are
    renumbered in order of first use -- a one-to-one renaming of names local to the module, so the
    circuit is the same. Repeated until nothing changes (a parent merges once its children have).
    The module's header (its name aside) and every other line must match exactly, so modules with
    different parameters, constants or ports never merge. Text outside modules (comments,
    attributes before ``module``, hand-written Verilog that is not yosys's) is kept as it is;
    attributes before a removed module go with it. The top module (the first, or the one marked
    ``(* top *)``) is never removed: it has no twin in a design.

    ``no_inline(name, instances, size)``: a module (after the merge; ``instances`` = how many
    copies the design holds, through every level; ``size`` = characters of its text) for which it
    is true gets Verilator's ``/*verilator no_inline_module*/``: Verilator inlines every module by
    default, so merged text alone still compiles to one copy of the code per instance; a module
    kept out of line is one C++ function set shared by all its instances (fewer instructions to
    cache per clock). A comment to every other tool."""
    lines = text.splitlines(keepends=True)
    chunks: list[tuple[str | None, list[str]]] = []   # (module name or None, lines)
    pending: list[str] = []
    tops: set[str] = set()
    cur: list[str] | None = None
    for ln in lines:
        if cur is not None:
            cur.append(ln)
            if ln.startswith("endmodule"):
                cur = None
            continue
        m = _MODULE_START.match(ln)
        if m:
            cur = [*pending, ln]
            chunks.append((m.group(1), cur))
            if any(re.search(r"\btop\b", a) for a in pending):
                tops.add(m.group(1))
            pending = []
        elif ln.lstrip().startswith("(*"):
            pending.append(ln)
        else:
            chunks.extend((None, [p]) for p in pending)
            pending = []
            chunks.append((None, [ln]))
    chunks.extend((None, [p]) for p in pending)
    names = [n for n, _ in chunks if n is not None]
    if len(set(names)) != len(names):    # not a file this pass understands: leave it alone
        return text
    body = {n: ls for n, ls in chunks if n is not None}
    rep = {n: n for n in names}

    def key(name: str) -> str:
        out, internal = [], {}
        for ln in body[name]:
            if ln.startswith("module"):
                ln = ln.replace(name, "<self>", 1)
            else:
                m = _INSTANCE.match(ln)
                if m and m.group(2) in rep:
                    ln = m.group(1) + rep[m.group(2)] + ln[m.end():]
            out.append(_INTERNAL.sub(lambda x: internal.setdefault(x.group(0), f"\\$<{len(internal)}>"), ln))
        return "".join(out)

    while True:
        seen: dict[str, str] = {}
        changed = False
        for n in names:
            if rep[n] != n:
                continue
            k = key(n)
            if k in seen and n not in tops:
                for o in names:   # n and everything merged into it now map to the earlier one
                    if rep[o] == n:
                        rep[o] = seen[k]
                changed = True
            else:
                seen.setdefault(k, n)
        if not changed:
            break
    kept = [n for n in names if rep[n] == n]
    uses = {n: [] for n in kept}   # module -> the modules instantiating it, once per instance
    for n in kept:
        for ln in body[n]:
            m = _INSTANCE.match(ln) if not ln.startswith("module") else None
            if m and m.group(2) in rep:
                uses[rep[m.group(2)]].append(n)

    @cache
    def copies(n: str) -> int:
        return sum(copies(p) for p in uses[n]) if uses[n] else 1

    out = []
    for n, ls in chunks:
        if n is not None and rep[n] != n:
            continue
        for ln in ls:
            m = _INSTANCE.match(ln) if n is not None and not ln.startswith("module") else None
            out.append(m.group(1) + rep[m.group(2)] + ln[m.end():] if m and m.group(2) in rep else ln)
            if (n is not None and no_inline is not None and _MODULE_START.match(ln)
                    and no_inline(n, copies(n), sum(map(len, ls)))):
                out.append("  /*verilator no_inline_module*/\n")
    return "".join(out)


def generate_verilog(name: str, **params) -> str:
    """Verilog text of block ``name``; the top module is ``name`` with ``-`` -> ``_``.

    Ports come from the component's signature (``amaranth.back.verilog.convert``);
    streams flatten to ``<port>__valid``, ``<port>__ready``, ``<port>__payload``.
    """
    from amaranth.back import verilog

    comp = make_block(name, **params)
    text = canonical_port_lists(_quietly(lambda: verilog.convert(comp, name=_module_name(name), emit_src=False),
                                         name))
    # hand-written Verilog the block instantiates (e.g. a RAM model) travels with it
    extra = comp.extra_verilog() if hasattr(comp, "extra_verilog") else ""
    return text + ("\n" + extra if extra else "")


def parse_params(params: tuple[str, ...], factory) -> dict:
    """``-p NAME=VALUE`` pairs -> keyword arguments typed by ``factory``'s signature: a parameter
    whose default is a bool takes true/false/1/0, an int default takes an integer, and so on;
    an unknown name is an error."""
    sig = inspect.signature(factory)
    out: dict = {}
    for p in params:
        if "=" not in p:
            raise RasterhwError(f"--param must be NAME=VALUE, not {p!r}")
        k, v = p.split("=", 1)
        if k not in sig.parameters:
            raise RasterhwError(f"no parameter {k!r}; parameters: {', '.join(sig.parameters)}")
        if k in out:
            raise RasterhwError(f"parameter {k!r} given twice")
        default = sig.parameters[k].default
        if isinstance(default, bool):
            low = v.lower()
            if low not in ("true", "false", "1", "0", "yes", "no"):
                raise RasterhwError(f"parameter {k!r} is true or false, not {v!r}")
            out[k] = low in ("true", "1", "yes")
        elif isinstance(default, int) or default is inspect.Parameter.empty:
            # ASCII digits with an optional sign, as --size reads them: no 0x40, no 1_000, no
            # Arabic-Indic or full-width digits (int() takes them all; issue 47)
            if re.fullmatch(r"[+-]?[0-9]+", v.strip(), re.ASCII):
                out[k] = int(v)
            elif isinstance(default, int):
                raise RasterhwError(f"parameter {k!r} is an integer in ASCII digits (e.g. {k}=24), not {v!r}")
            else:
                out[k] = v
        elif isinstance(default, float):
            try:
                out[k] = float(v)
            except ValueError:
                raise RasterhwError(f"parameter {k!r} is a number, not {v!r}") from None
        else:
            out[k] = v
    return out
