# amaranth: UnusedElaboratable=no
"""Verilog generation for the HDL blocks the machines register (``Machine.blocks``).

A block is a factory taking keyword parameters and returning a ``wiring.Component``; a
component that instantiates hand-written Verilog returns that source from its
``extra_verilog()`` method, and it is appended to the generated text.
"""

from __future__ import annotations

import inspect
from pathlib import Path

from amaranth.back import verilog
from amaranth.lib import wiring
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.registry import blocks, load

__all__ = ["block_names", "generate_verilog", "write_verilog", "make_block"]


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
    try:
        return factory(**params)
    except RasterhwError:
        raise
    except (ValueError, TypeError) as e:
        raise RasterhwError(f"block {name!r}: {e}") from e


def _module_name(name: str) -> str:
    return name.replace("-", "_")


def generate_verilog(name: str, **params) -> str:
    """Verilog text of block ``name``; the top module is ``name`` with ``-`` -> ``_``.

    Ports come from the component's signature (``amaranth.back.verilog.convert``);
    streams flatten to ``<port>__valid``, ``<port>__ready``, ``<port>__payload``.
    """
    comp = make_block(name, **params)
    text = verilog.convert(comp, name=_module_name(name), emit_src=False)
    # hand-written Verilog the block instantiates (e.g. a RAM model) travels with it
    extra = comp.extra_verilog() if hasattr(comp, "extra_verilog") else ""
    return text + ("\n" + extra if extra else "")


def write_verilog(name: str, path: str | Path, **params) -> Path:
    """Write :func:`generate_verilog` output to ``path``; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(generate_verilog(name, **params))
    return path
