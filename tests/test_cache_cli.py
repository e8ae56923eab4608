"""``rasterhw cache info|clean`` (sim/cacheinfo.py, sim/cli/cache.py): every entry with its kind,
design, size and last use; pruning by age and size, least recently used first, never an entry in
use; the cap after a run (RASTERHW_CACHE_MAX); bad sizes and ages are one line, exit 2."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest
from rasterhw.sim import cacheinfo, paths
from rasterhw.sim.cachefile import entry_of, read_entry, write_entry
from rasterhw.sim.cli.main import main

MB = 1 << 20
ROOT = Path(__file__).resolve().parents[1]


def _fill(path: Path, nbytes: int) -> Path:
    """A file of ``nbytes`` random bytes (they take disk space)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(os.urandom(nbytes))
    return path


def _age(top: Path, when: float) -> None:
    for p in [top, *top.rglob("*")] if top.is_dir() else [top]:
        os.utime(p, (when, when))


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    """A cache folder with one entry of each kind, last used 5, 4, 3, 2, 1 days ago (in that order)."""
    root = tmp_path / "cache"
    now = time.time()
    day = 86400.0
    tb = root / "tb-zbm-unit-0123456789"
    _fill(tb / "obj_dir" / "Vrasterhw_bench", MB)
    (tb / "build.json").write_text(json.dumps({"model": "tb-zbm-unit", "top": "rasterhw_bench"}))
    (root / "tb-zbm-unit-0123456789.lock").touch()
    _age(tb, now - 5 * day)
    write_entry(root / "verilog" / "pixelbus-0123456789abcdef.v", os.urandom(MB // 2), root=root)
    _age(root / "verilog", now - 4 * day)
    task = root / "tasks" / "ab" / ("ab" + "0" * 62 + ".json")
    task.parent.mkdir(parents=True)
    task.write_text(json.dumps({"task": {"kind": "sim", "name": "pxp", "params": {}}, "result": {"x": "y" * 4000}}))
    _age(root / "tasks", now - 3 * day)
    _fill(root / "synth-pixelbus-bank-0123456789" / "netlist.json", MB)
    _age(root / "synth-pixelbus-bank-0123456789", now - 2 * day)
    _fill(root / "pgo" / "tb-zbm-unit-pgogen-0123456789" / "a.gcda", MB // 4)
    _age(root / "pgo", now - 1 * day)
    monkeypatch.setattr(paths, "BUILD_ROOT", root)
    return root


def _json(argv, capsys) -> dict:
    try:
        main(argv)
    except SystemExit as e:
        assert not e.code, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def test_info_lists_every_entry_with_kind_design_size_and_last_use(cache, capsys):
    doc = _json(["cache", "info", "--json"], capsys)
    assert doc["schema"] == "rasterhw.cache-info/1" and doc["root"] == str(cache)
    got = [(e["kind"], e["design"], e["path"]) for e in doc["entries"]]
    # least recently used first
    assert got == [("verilator-build", "zbm-unit", "tb-zbm-unit-0123456789"),
                   ("verilog", "pixelbus", "verilog/pixelbus-0123456789abcdef.v"),
                   ("task-result", "pxp", "tasks/ab/ab" + "0" * 62 + ".json"),
                   ("synthesis", "pixelbus-bank", "synth-pixelbus-bank-0123456789"),
                   ("pgo-profile", "zbm-unit", "pgo/tb-zbm-unit-pgogen-0123456789")]
    sizes = {e["path"]: e["size_bytes"] for e in doc["entries"]}
    assert sizes["tb-zbm-unit-0123456789"] >= MB and sizes["verilog/pixelbus-0123456789abcdef.v"] >= MB // 2
    ages = [e["last_use_age_s"] for e in doc["entries"]]
    assert all(abs(a - (5 - i) * 86400) < 600 for i, a in enumerate(ages)), ages
    assert all(e["in_use"] is None for e in doc["entries"])
    assert doc["kinds"]["verilator-build"]["entries"] == 1
    assert doc["total_bytes"] >= sum(sizes.values())


def test_a_cache_hit_is_a_use(cache):
    v = cache / "verilog" / "pixelbus-0123456789abcdef.v"
    assert entry_of(v, cache) == v and entry_of(cache / "tb-zbm-unit-0123456789" / "obj_dir" / "x", cache) == \
        cache / "tb-zbm-unit-0123456789"
    before = {e.path.name: e.last_use for e in cacheinfo.entries(cache)}
    import rasterhw.sim.cachefile as cf

    old = cf.BUILD_ROOT
    cf.BUILD_ROOT = cache
    try:
        assert read_entry(v, what="a test text") is not None
    finally:
        cf.BUILD_ROOT = old
    after = {e.path.name: e.last_use for e in cacheinfo.entries(cache)}
    assert after[v.name] > before[v.name] + 3 * 86400   # read now, written four days ago
    assert after["tb-zbm-unit-0123456789"] == before["tb-zbm-unit-0123456789"]


def test_clean_by_size_removes_the_least_recently_used_first(cache, capsys):
    total = cacheinfo.total_bytes(cache)
    cap = total - MB // 2    # the oldest entry (1 MB) is enough
    doc = _json(["cache", "clean", "--max-size", str(cap), "--json"], capsys)
    assert doc["schema"] == "rasterhw.cache-clean/1"
    assert [e["path"] for e in doc["removed"]] == ["tb-zbm-unit-0123456789"]
    assert not (cache / "tb-zbm-unit-0123456789").exists() and (cache / "verilog").is_dir()
    assert doc["total_bytes"] == cacheinfo.total_bytes(cache) <= cap and not doc["over_cap"]


def test_clean_by_age(cache, capsys):
    doc = _json(["cache", "clean", "--older-than", "2.5d", "--json"], capsys)
    assert sorted(e["kind"] for e in doc["removed"]) == ["task-result", "verilator-build", "verilog"]
    assert not (cache / "verilog" / "pixelbus-0123456789abcdef.v.sha256").exists()   # its record went with it
    left = [e.kind for e in cacheinfo.entries(cache)]
    assert left == ["synthesis", "pgo-profile"]


def test_clean_never_removes_an_entry_in_use(cache, capsys):
    # its build lock held by another running process
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time; from filelock import FileLock; "
                               f"lock = FileLock({str(cache / 'tb-zbm-unit-0123456789.lock')!r}); lock.acquire(); "
                               "print('held', flush=True); time.sleep(60)"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        # a run folder of a running process (this one) in the synthesis folder; one of a process gone in the
        # profile folder does not count
        host = cacheinfo._HOST
        (cache / "synth-pixelbus-bank-0123456789" / f"run-{host}-{os.getpid()}-x").mkdir()
        dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True,
                              text=True, check=True)
        (cache / "pgo" / "tb-zbm-unit-pgogen-0123456789" / f"run-{host}-{dead.stdout.strip()}-x").mkdir()
        doc = _json(["cache", "clean", "--all", "--json"], capsys)
    finally:
        holder.kill()
        holder.wait()
    kept = {e["path"]: e["in_use"] for e in doc["kept_in_use"]}
    assert kept == {"tb-zbm-unit-0123456789": "its build lock is held",
                    "synth-pixelbus-bank-0123456789": f"process {os.getpid()} runs in it"}
    assert (cache / "tb-zbm-unit-0123456789" / "build.json").exists()
    assert not (cache / "pgo" / "tb-zbm-unit-pgogen-0123456789").exists()
    assert doc["over_cap"]


@pytest.mark.parametrize("argv, says", [
    (["--max-size", "banana"], "--max-size must be a size"),
    (["--max-size", "-5M"], "--max-size must be a size"),
    (["--older-than", "3 fortnights"], "--older-than must be an age"),
    ([], "say what to remove"),
    (["--all", "--max-size", "1G"], "--all removes every entry"),
])
def test_bad_input_is_one_line_and_exit_2(cache, capsys, argv, says):
    with pytest.raises(SystemExit) as e:
        main(["cache", "clean", *argv])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.startswith(f"error: {says}") and err.count("\n") == 1, err
    assert (cache / "tb-zbm-unit-0123456789").exists()   # nothing removed


def test_sizes_and_ages_parse():
    assert cacheinfo.parse_size("100M") == 100 * MB and cacheinfo.parse_size("1.5g") == 3 * (1 << 29)
    assert cacheinfo.parse_size("500KB") == 500 * 1024 and cacheinfo.parse_size("4096") == 4096
    assert cacheinfo.parse_age("12h") == 43200 and cacheinfo.parse_age("2") == 2 * 86400


def _rasterhw(args, cache, **env):
    e = {k: v for k, v in os.environ.items() if not k.startswith("RASTERHW_")}
    e.update(PYTHONPATH=os.environ.get("PYTHONPATH", ""), RASTERHW_CACHE=str(cache), **env)
    return subprocess.run([sys.executable, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True,
                          env=e, timeout=600)


def test_the_cap_after_a_run_and_a_run_after_clean_still_passes(cache):
    bad = _rasterhw(["scenes"], cache, RASTERHW_CACHE_MAX="lots")
    assert bad.returncode == 2 and bad.stderr.startswith("error: RASTERHW_CACHE_MAX must be a size"), bad.stderr
    assert bad.stdout == ""
    r = _rasterhw(["scenes", "--json"], cache, RASTERHW_CACHE_MAX="2M")
    assert r.returncode == 0, r.stderr
    assert cacheinfo.total_bytes(cache) <= 2 * MB
    assert not (cache / "tb-zbm-unit-0123456789").exists() and (cache / "pgo").exists()   # the oldest went first
    r = _rasterhw(["cache", "clean", "--max-size", "100K"], cache)
    assert r.returncode == 0 and cacheinfo.total_bytes(cache) <= 100 * 1024, r.stderr
    r = _rasterhw(["sim", "pixelbus", "--scene", "snu-100px", "--size", "16x16", "--engine", "pysim", "--json",
                   "-o", str(cache.parent / "f.png")], cache)
    assert r.returncode == 0 and json.loads(r.stdout)["mismatches"] == 0, r.stderr[-2000:]
