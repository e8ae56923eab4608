"""Generated Verilog cached on disk by a digest of the design's parameters and source.

``amaranth.back.verilog.convert`` of a large block takes tens of seconds (the sparse video
processor ~25 s, the ZB/M unit more); a scene run whose Verilator model is already built
should not pay it again. :func:`convert_cached` keys the text on the block name, its
parameters, the Amaranth version and the bytes of every Python file under ``hdl/`` and
``golden_model/`` (the formats modules the HDL takes its widths from live there), so any
change to the design gives a fresh conversion and an unchanged design never converts twice.
Files go to ``build/verilog/<name>-<digest>.v``, written atomically.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from functools import cache
from pathlib import Path

__all__ = ["convert_cached", "source_digest"]

PKG_ROOT = Path(__file__).resolve().parent.parent


@cache
def source_digest() -> str:
    """Digest of every ``.py`` file under ``hdl/`` and ``golden_model/`` (once per process)."""
    import amaranth

    h = hashlib.sha1(amaranth.__version__.encode())
    for sub in ("hdl", "golden_model"):
        for f in sorted((PKG_ROOT / sub).rglob("*.py")):
            h.update(str(f.relative_to(PKG_ROOT)).encode())
            h.update(f.read_bytes())
    return h.hexdigest()


def convert_cached(name: str, factory: Callable[[], object], *, params: Mapping[str, object],
                   module: str, convert: Callable[[object, str], str] | None = None) -> str:
    """Verilog text of ``factory()`` (an elaboratable) with top module ``module``.

    ``params`` must name everything the design depends on besides the source (the factory's
    arguments). ``convert(design, module)`` defaults to ``amaranth.back.verilog.convert``."""
    from rasterhw.sim.runner import REPO_ROOT

    key = json.dumps({"name": name, "module": module, "params": dict(params)}, sort_keys=True, default=str)
    digest = hashlib.sha1((source_digest() + key).encode()).hexdigest()[:16]
    path = REPO_ROOT / "build" / "verilog" / f"{name}-{digest}.v"
    if path.exists():
        return path.read_text()
    if convert is None:
        from amaranth.back import verilog

        def convert(design, mod):
            return verilog.convert(design, name=mod)
    from rasterhw.sim.outfile import write_text

    text = convert(factory(), module)
    write_text(path, text)
    return text
