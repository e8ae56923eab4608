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

from amaranth.back import verilog
from amaranth.hdl import UnusedElaboratable
from amaranth.lib import wiring
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.registry import blocks, load

__all__ = ["block_names", "canonical_port_lists", "generate_verilog", "make_block", "parse_params"]


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
            try:
                out[k] = int(v, 0)
            except ValueError:
                if isinstance(default, int):
                    raise RasterhwError(f"parameter {k!r} is an integer, not {v!r}") from None
                out[k] = v
        elif isinstance(default, float):
            try:
                out[k] = float(v)
            except ValueError:
                raise RasterhwError(f"parameter {k!r} is a number, not {v!r}") from None
        else:
            out[k] = v
    return out
