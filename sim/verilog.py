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
from pathlib import Path

from amaranth.back import verilog
from amaranth.hdl import UnusedElaboratable
from amaranth.lib import wiring
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.registry import blocks, load

__all__ = ["block_names", "canonical_port_lists", "generate_verilog", "write_verilog", "make_block"]


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
    msg = None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnusedElaboratable)
        try:
            return build()
        except RasterhwError as e:
            msg = str(e)
        except (ValueError, TypeError) as e:
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
    return _MODULE_HEADER.sub(fix, text)


def generate_verilog(name: str, **params) -> str:
    """Verilog text of block ``name``; the top module is ``name`` with ``-`` -> ``_``.

    Ports come from the component's signature (``amaranth.back.verilog.convert``);
    streams flatten to ``<port>__valid``, ``<port>__ready``, ``<port>__payload``.
    """
    comp = make_block(name, **params)
    text = canonical_port_lists(_quietly(lambda: verilog.convert(comp, name=_module_name(name), emit_src=False),
                                         name))
    # hand-written Verilog the block instantiates (e.g. a RAM model) travels with it
    extra = comp.extra_verilog() if hasattr(comp, "extra_verilog") else ""
    return text + ("\n" + extra if extra else "")


def write_verilog(name: str, path: str | Path, **params) -> Path:
    """Write :func:`generate_verilog` output to ``path`` (from the cache of generated Verilog,
    ``sim/verilog_cache.py``, when this design and these parameters were converted before);
    return the path."""
    from rasterhw.sim.outfile import write_text
    from rasterhw.sim.verilog_cache import generate_cached

    return write_text(path, generate_cached(name, **params))  # whole or not at all
