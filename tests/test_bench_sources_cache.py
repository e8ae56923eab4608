"""The Verilator engine's bench-top key (``sim/engines/verilator.py bench_sources``) keeps each
testbench's transitive sources in a cache entry of its own (``verilog_cache.closure_cached``:
``cachefile.write_entry``, SHA-256 checked) and reuses them only while every file and folder of the
closure is as it was and the entry is the one written."""

from __future__ import annotations

import json

from rasterhw.sim import cachefile
from rasterhw.sim.engines import verilator
from rasterhw.sim.engines.verilog_cache import module_sources
from rasterhw.sim.sparse.testbench import MatrixFrameBench


def _entry(tmp_path):
    (path,) = tmp_path.glob("bench-sources-*.json")
    return path, json.loads(path.read_text())


def _plant(path, entry) -> None:
    """Write ``entry`` with a matching SHA-256 record (an entry the cache itself wrote)."""
    cachefile.write_entry(path, json.dumps(entry).encode())


def test_cached_closure_is_the_parsed_one_and_a_changed_file_is_found_again(tmp_path, monkeypatch):
    monkeypatch.setattr(verilator, "_CLOSURES", tmp_path / "bench-sources")
    monkeypatch.setattr(cachefile, "BUILD_ROOT", tmp_path)
    tb = MatrixFrameBench()
    first = verilator.bench_sources(tb)
    roots = [verilator.Path(verilator.__file__)] + [verilator._class_file(c) for c in type(tb).__mro__
                                                      if verilator._class_file(c) is not None]
    assert first == module_sources(roots) and len(first) > 10
    path, entry = _entry(tmp_path)
    assert sorted(entry["files"]) == sorted(map(str, first))
    assert cachefile.read_entry(path, what="test") is not None   # written with its record
    # a reused entry: its file list is what bench_sources returns (planted, so a reuse shows)
    entry["files"] = entry["files"][:3]
    _plant(path, entry)
    assert verilator.bench_sources(tb) == [verilator.Path(f) for f in entry["files"]]
    # one file's stamp no longer the file's: the closure is parsed again
    some = entry["files"][0]
    entry["stamps"][some] = [0, 0]
    _plant(path, entry)
    assert verilator.bench_sources(tb) == first


def test_a_damaged_entry_is_found_again_not_served(tmp_path, monkeypatch, capsys):
    """Valid JSON with other content than its SHA-256 record (an edit, a bad disk) is said in one
    line and found again; the stamps alone would have served it."""
    monkeypatch.setattr(verilator, "_CLOSURES", tmp_path / "bench-sources")
    monkeypatch.setattr(cachefile, "BUILD_ROOT", tmp_path)
    tb = MatrixFrameBench()
    first = verilator.bench_sources(tb)
    path, entry = _entry(tmp_path)
    entry["files"] = entry["files"][:3]                    # stamps still true: only the record can tell
    path.write_text(json.dumps(entry))
    capsys.readouterr()
    assert verilator.bench_sources(tb) == first
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "does not match the SHA-256" in err and str(path) in err
    assert _entry(tmp_path)[1]["files"] == [str(f) for f in first]   # written again, whole
    assert cachefile.read_entry(path, what="test") is not None
    # one entry per set of roots: another testbench gets its own file, the first stays
    from rasterhw.sim.zbm.testbench import UnitBench

    verilator.bench_sources(UnitBench())
    assert len(list(tmp_path.glob("bench-sources-*.json"))) == 2
