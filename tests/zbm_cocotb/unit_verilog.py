"""Generated Verilog of the ZB/M unit and chip benches, from the one cache of generated Verilog
(``sim/engines/verilog_cache.py``): the chip, the head and tail units of a chain and the chain's
top (``chain_flat.py: ChainFlat``). The simulators read files: each text is written once
to ``build/zbm-verilog/<module>-<digest of the text>.v``."""

from __future__ import annotations

import hashlib
from pathlib import Path

from amaranth.back import verilog
from rasterhw.golden_model.zbm import formats as F
from rasterhw.sim.engines.verilog import canonical_port_lists, generate_verilog
from rasterhw.sim.engines.verilog_cache import convert_cached, generate_cached
from rasterhw.sim.outfile import write_text
from rasterhw.sim.paths import REPO_ROOT

from zbm_cocotb import chain_flat
from zbm_cocotb.chain_flat import ChainFlat

__all__ = ["chain_verilog", "chip_verilog"]

#: the chain top's own source is part of its design (the cache keys the unit's sources)
_CHAIN_SELF = hashlib.sha1(Path(chain_flat.__file__).read_bytes()).hexdigest()[:12]


def _file(module: str, text: str) -> Path:
    """``text`` as a file the simulators read, named by its content (written once)."""
    path = REPO_ROOT / "build" / "zbm-verilog" / f"{module}-{hashlib.sha1(text.encode()).hexdigest()[:12]}.v"
    if not path.exists():
        write_text(path, text)
    return path


def chip_verilog(*, interleave: int, chip: int, width: int) -> Path:
    """The generated ``zbm-chip`` (module ``zbm_chip``)."""
    return _file("zbm_chip", generate_cached("zbm-chip", interleave=interleave, chip=chip, width=width))


def chain_verilog(*, interleave: int, width: int, height: int, units: int = 1,
                  capacity: int = F.AEP_CAPACITY, schedule: str = "overlap") -> list[Path]:
    """Verilog sources of ``units`` chained ``zbm-unit``\\s: the head ``zbm_unit``, the others
    (``head=False``, with merge inputs) renamed ``zbm_unit_tail`` so both can live in one
    simulation, and the chain's top ``zbm_chain_flat`` (the cocotb unit bench's)."""
    p = {"interleave": interleave, "width": width, "height": height, "capacity": capacity, "schedule": schedule}
    head = generate_cached("zbm-unit", head=True, **p)
    srcs = [_file("zbm_unit", head)]
    if units > 1:
        tail = convert_cached("zbm-unit", lambda: None, params={**p, "head": False}, module="zbm_unit_tail",
                              convert=lambda _d, _m: generate_verilog("zbm-unit", head=False, **p)
                              .replace("zbm_unit", "zbm_unit_tail"))
        srcs.append(_file("zbm_unit_tail", tail))
    ovf = "overflow" in head.split("module zbm_unit(", 1)[1].split(";", 1)[0]
    top = convert_cached("zbm-unit", lambda: ChainFlat(interleave=interleave, units=units, has_overflow=ovf),
                         params={"interleave": interleave, "units": units, "overflow": ovf, "top": _CHAIN_SELF},
                         module="zbm_chain_flat",
                         convert=lambda d, mod: verilog.convert(d, name=mod, ports=d.ports, emit_src=False))
    # (its port order must not depend on the process: the build's key is the text)
    top = canonical_port_lists(top)
    return srcs + [_file("zbm_chain_flat", top)]
