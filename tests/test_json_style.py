"""One JSON style (issue 30 item 5; ``docs/architecture.md``, "JSON output"): every command's
``--json`` on a tiny input is one line of JSON whose keys are snake_case with the unit last, a
golden model's value of a measured key ``K`` is ``K_golden``, and clocks are in Hz (``_hz``; place
and route's Fmax ``_mhz``). Maps keyed by names (blocks, stages, cells) are the one exception."""

from __future__ import annotations

import json
import re

import pytest
from rasterhw.sim.cli.main import ARCHS, main

SNAKE = re.compile(r"[a-z][a-z0-9_]*\Z")
#: fields whose value is a map keyed by names of things (block names, stage labels, FPGA cells):
#: those keys are the things' own names
NAME_MAPS = {"blocks", "proofs", "soak", "stages_s", "busy_s", "share_of_frame", "available", "utilization",
             "fmax_mhz", "ports", "sims", "kinds"}
#: unit spellings the style does not use (seconds are _s, milliseconds _ms, frequencies _hz / _mhz)
BAD_UNITS = re.compile(r"_(sec|secs|seconds|msec|millis|khz|ghz|freq|frequency|time_s)\Z")


def style_problems(obj, path: str = "") -> list[str]:
    """Every key of ``obj`` (walked through dicts and lists) that breaks the style."""
    bad = []
    if isinstance(obj, dict):
        for k, v in obj.items():
            where = f"{path}/{k}"
            if not SNAKE.match(str(k)):
                bad.append(f"{where}: not snake_case")
            if BAD_UNITS.search(str(k)):
                bad.append(f"{where}: unit spelled differently from _s/_ms/_hz")
            if str(k).startswith("golden_") and not str(k).endswith("_s"):
                bad.append(f"{where}: a golden value is K_golden")
            if re.search(r"(^|_)clock(_|$)", str(k)) and isinstance(v, (int, float)) and not isinstance(v, bool) \
                    and not re.search(r"_(hz|mhz)\Z", str(k)):
                bad.append(f"{where}: a clock is in _hz")
            if k in NAME_MAPS and isinstance(v, dict):
                for name, inner in v.items():
                    bad += style_problems(inner, f"{where}/{name}")
            else:
                bad += style_problems(v, where)
    elif isinstance(obj, list):
        for x in obj:
            bad += style_problems(x, path + "[]")
    return bad


def _json_of(argv, capsys):
    try:
        main(argv)
    except SystemExit as e:
        assert not e.code, capsys.readouterr().err
    out = capsys.readouterr().out
    lines = out.strip().splitlines()
    assert len(lines) == 1, f"not one line: {out[:300]}"
    return json.loads(lines[0])


def _check(obj, shape):
    """Every document is an object with its schema and version first (issue 53 item 5); a
    command that lists things (``shape`` list) gives its rows under ``rows``."""
    from rasterhw.sim.cli.jsonout import SCHEMAS
    from rasterhw.sim.version import version

    assert isinstance(obj, dict), type(obj)
    assert list(obj)[:2] == ["schema", "version"], list(obj)[:3]
    m = re.fullmatch(r"rasterhw\.([a-z-]+)/([0-9]+)", obj["schema"])
    assert m and SCHEMAS[m.group(1)] == int(m.group(2)), obj["schema"]
    assert obj["version"] == version()
    if shape is list:
        rows = obj["rows"]
        assert set(obj) == {"schema", "version", "rows"}
        assert rows and all(isinstance(r, dict) for r in rows)   # a list is rows: objects
    else:
        assert "rows" not in obj
    problems = style_problems(obj)
    assert not problems, problems


def test_every_command_with_json_has_a_schema():
    """Every command (and subcommand) that takes --json is in SCHEMAS, under the name its document
    carries; every name in SCHEMAS is a command."""
    import click
    from rasterhw.sim.cli.jsonout import SCHEMAS, schema
    from rasterhw.sim.cli.main import cli

    found = set()

    def walk(cmd, names):
        if isinstance(cmd, click.Group):
            for name, sub in cmd.commands.items():
                walk(sub, [*names, name])
        elif any("--json" in p.opts for p in cmd.params):
            found.add("-".join(names))

    walk(cli, [])
    assert found == set(SCHEMAS)
    assert schema("cache-info") == "rasterhw.cache-info/1"
    with pytest.raises(RuntimeError, match="no schema"):
        schema("nothing")


def test_the_walker_finds_what_breaks_the_style():
    bad = style_problems({"wallTime": 1, "build_seconds": 2, "golden_cycles": 3, "clock": 4.0,
                          "blocks": {"pixelbus-bank": {"ok": 1, "Bad-Key": 2}}, "rows": [{"x-y": 1}]})
    assert len(bad) == 6, bad
    assert not style_problems({"wall_s": 1, "cycles_golden": 2, "golden_wall_s": 3, "clock_hz": 4,
                               "i860_clocks": {"triangle": 1}, "fmax_mhz": {"sync": 50.0}})


@pytest.mark.parametrize("argv, shape", [
    (["scenes", "--json"], list),
    (["machines", "--json"], list),
])
def test_listing_commands(argv, shape, capsys):
    _check(_json_of(argv, capsys), shape)


@pytest.mark.parametrize("arch", ARCHS)
def test_render_of_every_arch(arch, tmp_path, capsys):
    res = _json_of(["render", "c50", "--arch", arch, "--size", "16x16", "--json", "-o", str(tmp_path / "a.png")],
                   capsys)
    _check(res, dict)


def test_compare(tmp_path, capsys):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    _json_of(["render", "c50", "--size", "16x16", "--json", "-o", str(a)], capsys)
    _json_of(["render", "c50", "--arch", "zbm", "--size", "16x16", "--json", "-o", str(b)], capsys)
    _check(_json_of(["compare", str(a), str(b), "--json"], capsys), dict)


@pytest.mark.parametrize("argv", [
    ["sim", "pixelbus", "--scene", "snu-100px", "--size", "16x16", "--engine", "pysim"],
    ["sim", "pxp", "--scene", "experts-solid-5", "--size", "16x16", "--engine", "pysim"],
    ["sim", "experts", "--scene", "experts-solid-5", "--size", "16x16", "--engine", "pysim"],
    pytest.param(["sim", "zbm", "--scene", "c50", "--size", "16x16", "--engine", "pysim"], marks=pytest.mark.slow),
    pytest.param(["sim", "sparse", "--scene", "c50", "--size", "16x16", "--matrix", "2x2", "--engine", "pysim"],
                 marks=pytest.mark.slow),
], ids=["pixelbus", "pxp", "experts", "zbm", "sparse"])
def test_sim(argv, tmp_path, capsys):
    extra = [] if "sparse" in argv else ["-o", str(tmp_path / "a.png")]
    from rasterhw.sim.cli.jsonout import SIM_JSON_KEYS

    res = _json_of([*argv, "--json", *extra], capsys)
    _check(res, dict)
    # one key set on every machine and engine (issue 46): the common keys in order, then the image
    assert tuple(res)[:len(SIM_JSON_KEYS)] == SIM_JSON_KEYS and set(res) - set(SIM_JSON_KEYS) <= {"image"}
    assert res["schema"] == "rasterhw.sim/1" and res["block"] == argv[1] and res["engine"] == "pysim"
    assert isinstance(res["mismatches"], int) and res["mismatches"] == 0 and res["pixels_compared"] > 0
    assert res["sim_cycles"] >= res["cycles"] > 0 and res["sim_cpu_s"] > 0
    assert res["cycles_per_cpu_s"] == pytest.approx(res["sim_cycles"] / res["sim_cpu_s"])
    # no value under two names: the older names are gone, top level and extra
    for old in ("sim_s", "golden_cycles", "run_s", "build_s", "wall_s", "cycles_per_s", "sim_cycles"):
        assert old not in res["extra"], old
    if argv[1] == "pixelbus":    # a machine's own figures are in extra, golden values as K_golden
        assert "cycles_golden" in res["extra"]


def test_cache(tmp_path, capsys, monkeypatch):
    from rasterhw.sim import paths

    monkeypatch.setattr(paths, "BUILD_ROOT", tmp_path)
    (tmp_path / "tb-x-0123456789").mkdir()
    _check(_json_of(["cache", "info", "--json"], capsys), dict)
    _check(_json_of(["cache", "clean", "--older-than", "1d", "--json"], capsys), dict)


def test_sweep(tmp_path, capsys):
    res = _json_of(["sweep", "render:experts", "--param", "sn=1,2", "--scene", "c50", "--size", "16x16",
                    "--scheduler", "serial", "--store", str(tmp_path / "store"), "--json"], capsys)
    _check(res, dict)
    assert len(res["points"]) == 2


def test_flow_commands_print_through_the_same_writer():
    """synth, fpga and prove (sim/cli/flow.py) print with the one writer: one line, NumPy numbers as
    numbers (before: indented, and anything unknown turned into a string)."""
    from rasterhw.sim.cli import flow, jsonout

    assert flow.emit_json is jsonout.emit_json


def test_sim_json_common_keys_and_extra():
    """sim_json: the common keys from the driver and the engine runs, the driver's timings replaced
    by the engine runs' (one name per value), everything else in extra; a driver without a common
    key is a programming error."""
    from rasterhw.sim.cli.jsonout import SIM_JSON_KEYS, sim_json
    from rasterhw.sim.engines import Tally
    from rasterhw.sim.testbench import Run

    runs = Tally([Run("verilator", {"o": [1]}, {"o": [99]}, run_s=0.5, build_s=2.0, cpu_s=0.25),
                  Run("verilator", {"o": [1]}, {"o": [49]}, run_s=0.5, build_s=0.0, cpu_s=0.25)])
    res = sim_json("zbm", "c50", {"engine": "verilator", "cycles": 100, "clock_hz": 25e6, "pixels_compared": 9,
                                  "mismatches": 0, "sim_s": 7.0, "run_s": 7.0, "units": 2, "image": "a.png"},
                   runs, 3.0)
    assert tuple(res) == (*SIM_JSON_KEYS, "image") and res["extra"] == {"units": 2}
    assert (res["sim_cycles"], res["sim_cpu_s"], res["run_s"], res["build_s"]) == (150, 0.5, 1.0, 2.0)
    assert res["cycles_per_cpu_s"] == 300 and res["cycles_per_s"] == 150 and res["cycle_mismatches"] is None
    with pytest.raises(RuntimeError, match="no 'mismatches'"):
        sim_json("zbm", "c50", {"engine": "pysim", "cycles": 1, "clock_hz": None, "pixels_compared": 1}, runs, 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("argv, shape", [
    (["synth", "pixelbus-bank", "--json"], dict),
    (["prove", "pixelbus-bank", "--json"], dict),
    (["fpga", "pixelbus-bank", "--json"], dict),
    (["report", "vzbuf", "--fast", "--json"], list),
    (["soak", "--pixels", "256", "--block", "pixelbus", "--seed", "3", "--scheduler", "serial", "--json"], list),
    (["bench", "--json"], list),
], ids=["synth", "prove", "fpga", "report", "soak", "bench"])
def test_slow_commands(argv, shape, tmp_path, capsys, monkeypatch):
    if argv[0] == "report":
        argv = [*argv, "--out", str(tmp_path)]
    if argv[0] == "soak":
        argv = [*argv, "--store", str(tmp_path / "store")]
    _check(_json_of(argv, capsys), shape)
