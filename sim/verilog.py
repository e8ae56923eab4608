# amaranth: UnusedElaboratable=no
"""Verilog generation for the HDL blocks: a name -> factory registry.

Add a block by adding an entry to :data:`BLOCKS` (a factory taking keyword parameters
and returning a ``wiring.Component``), and, if it instantiates hand-written Verilog
modules, their source to :data:`EXTRA_VERILOG`.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from pathlib import Path

from amaranth.back import verilog
from amaranth.lib import wiring
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.hdl.snu.pixelbus import PixelBus
from rasterhw.hdl.snu.pixelbus_bank import RAM_VERILOG, PixelBusBank
from rasterhw.hdl.zbm.chip import ZbmChip
from rasterhw.hdl.zbm.seggen import ZbmSegmentGenerator
from rasterhw.hdl.zbm.unit import ZbmUnit

__all__ = ["BLOCKS", "EXTRA_VERILOG", "generate_verilog", "write_verilog", "make_block"]

BLOCKS: dict[str, Callable[..., wiring.Component]] = {
    "pixelbus-bank": PixelBusBank,
    "pixelbus": PixelBus,
    "zbm-chip": ZbmChip,
    "zbm-seggen": ZbmSegmentGenerator,
    "zbm-unit": ZbmUnit,
}

# Hand-written Verilog a block needs next to its generated code: name -> callable(component)
# returning the extra source text ("" if none).
EXTRA_VERILOG: dict[str, Callable[[wiring.Component], str]] = {
    "pixelbus-bank": lambda c: RAM_VERILOG if c.ram == "verilog" else "",
    "pixelbus": lambda c: RAM_VERILOG if c.ram == "verilog" else "",
}


def make_block(name: str, **params) -> wiring.Component:
    """Build the registered block ``name`` with ``params``; bad names/params raise ``RasterhwError``."""
    try:
        factory = BLOCKS[name]
    except KeyError:
        raise RasterhwError(f"unknown block {name!r}; known: {', '.join(sorted(BLOCKS))}") from None
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
    extra = EXTRA_VERILOG.get(name, lambda c: "")(comp)
    return text + ("\n" + extra if extra else "")


def write_verilog(name: str, path: str | Path, **params) -> Path:
    """Write :func:`generate_verilog` output to ``path``; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(generate_verilog(name, **params))
    return path
