"""The Verilator engine's cache key of a bench top (``sim/engines/verilator.py: _design``): every
Python source the design is made from counts, the testbench module's imports included, so an
edited adapter module never reuses a stale build (issue 25: the key held the testbench module's
own bytes only)."""

from __future__ import annotations

import importlib
import sys

import pytest
from rasterhw.sim.engines import verilator
from rasterhw.sim.engines.verilog_cache import PKG_ROOT
from rasterhw.sim.snu.testbench import FrameBench

TB = '''from rasterhw.sim.testbench import Testbench

from .adapter import WIDTH


class KeyBench(Testbench):
    """A throwaway testbench whose DUT adapter lives in another module."""

    block = "pixelbus"
'''


def _key(monkeypatch, tb) -> dict:
    """The key ``_design`` gives ``convert_cached`` for ``tb`` (nothing is converted)."""
    seen = []

    def fake(name, factory, *, params, module, convert=None):
        seen.append(dict(params))
        return "// not converted\n"

    monkeypatch.setattr(verilator, "convert_cached", fake)
    verilator.bench_design(tb, {"width": 16}, {"i": 16}, {"o": 16}, False)
    return seen[-1]


@pytest.fixture
def throwaway(tmp_path, monkeypatch):
    """A package ``keypkg`` in ``tmp_path``: a testbench module and the adapter module it imports."""
    pkg = tmp_path / "keypkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "adapter.py").write_text("WIDTH = 8\n")
    (pkg / "tb.py").write_text(TB)
    monkeypatch.syspath_prepend(str(tmp_path))
    yield pkg, importlib.import_module("keypkg.tb").KeyBench()
    for m in ("keypkg.tb", "keypkg.adapter", "keypkg"):
        sys.modules.pop(m, None)


def test_an_edited_adapter_module_gives_a_new_key(throwaway, monkeypatch):
    pkg, tb = throwaway
    first = _key(monkeypatch, tb)
    assert _key(monkeypatch, tb) == first                       # nothing changed: the same build
    (pkg / "adapter.py").write_text("WIDTH = 9\n")               # the adapter the testbench imports
    edited = _key(monkeypatch, tb)
    assert edited != first
    (pkg / "adapter.py").write_text("WIDTH = 8\n")               # back as it was: the first key again
    assert _key(monkeypatch, tb) == first
    (pkg / "tb.py").write_text(TB + "\n# a comment\n")            # the testbench module itself counts too
    assert _key(monkeypatch, tb) != first


def test_the_frame_bench_key_covers_its_adapter_and_read_out():
    """The SNU frame's bench top: its adapter and read-out modules (imported by the testbench
    module, not by the block) and the engine's own module are in the key's sources."""
    rel = {str(f.relative_to(PKG_ROOT)) for f in verilator.bench_sources(FrameBench()) if PKG_ROOT in f.parents}
    assert {"sim/snu/frame_adapter.py", "sim/engines/readout.py", "sim/snu/testbench.py", "sim/testbench.py",
            "sim/engines/verilator.py"} <= rel
    # another machine's modules do not rebuild it
    assert not any(r.startswith(("sim/zbm/", "hdl/zbm/", "sim/sparse/")) for r in rel)
