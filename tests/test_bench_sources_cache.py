"""The Verilator engine's bench-top key (``sim/engines/verilator.py bench_sources``) keeps each
testbench's transitive sources in a file and reuses them only while every file and folder of the
closure is as it was."""

from __future__ import annotations

import json

from rasterhw.sim.engines import verilator
from rasterhw.sim.engines.verilog_cache import module_sources
from rasterhw.sim.sparse.testbench import MatrixFrameBench


def test_cached_closure_is_the_parsed_one_and_a_changed_file_is_found_again(tmp_path, monkeypatch):
    monkeypatch.setattr(verilator, "_CLOSURES", tmp_path / "bench-sources.json")
    tb = MatrixFrameBench()
    first = verilator.bench_sources(tb)
    roots = [verilator.Path(verilator.__file__)] + [verilator._class_file(c) for c in type(tb).__mro__
                                                      if verilator._class_file(c) is not None]
    assert first == module_sources(roots) and len(first) > 10
    kept = json.loads((tmp_path / "bench-sources.json").read_text())
    (entry,) = kept.values()
    assert sorted(entry["files"]) == sorted(map(str, first))
    # a reused entry: its file list is what bench_sources returns (planted, so a reuse shows)
    entry["files"] = entry["files"][:3]
    (tmp_path / "bench-sources.json").write_text(json.dumps(kept))
    assert verilator.bench_sources(tb) == [verilator.Path(f) for f in entry["files"]]
    # one file's stamp no longer the file's: the closure is parsed again
    some = entry["files"][0]
    entry["stamps"][some] = [0, 0]
    (tmp_path / "bench-sources.json").write_text(json.dumps(kept))
    assert verilator.bench_sources(tb) == first
