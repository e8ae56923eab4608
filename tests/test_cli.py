"""The command line as a user meets it: JSON results, and one-line errors for bad input."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

PY = sys.executable


def run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


@pytest.mark.parametrize("scene,polys", [("c300", 1801), ("sp27", 2701)])
def test_render_reference_json(tmp_path, scene, polys):
    out = tmp_path / f"{scene}.png"
    r = run("render", scene, "--arch", "reference", "--json", "-o", str(out))
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    for key in ("scene", "arch", "width", "height", "polygons_in", "polygons_drawn", "pixels_written", "wall_s"):
        assert key in res
    assert (res["width"], res["height"]) == (512, 512)
    assert res["polygons_in"] == polys
    assert 0 < res["polygons_drawn"] < polys
    assert res["pixels_written"] > 0
    assert out.stat().st_size > 0


def test_render_is_deterministic(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert run("render", "c50", "-o", str(a)).returncode == 0
    assert run("render", "c50", "-o", str(b)).returncode == 0
    assert a.read_bytes() == b.read_bytes()
    r = run("compare", str(a), str(b), "--json")
    assert r.returncode == 0 and json.loads(r.stdout)["differing_pixels"] == 0


def test_scenes_lists_counts():
    r = run("scenes", "--json")
    assert r.returncode == 0, r.stderr
    rows = {row["name"]: row for row in json.loads(r.stdout)["rows"]}
    for name in ("c50", "c100", "c150", "c200", "c250", "c300", "sp27", "sp5", "sp8", "zbm-5x5",
                 "snu-100px", "experts-1000", "experts-2000"):
        assert name in rows
    assert rows["c300"]["polygons"] == 1801 and rows["sp27"]["polygons"] == 2701


def _assert_one_line_error(r: subprocess.CompletedProcess) -> None:
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr


BAD_OBJS = {
    "nan.obj": "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n",
    "empty.obj": "",
    "twovert.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n",
    "huge.obj": "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n",
}


@pytest.mark.parametrize("name", sorted(BAD_OBJS))
def test_bad_mesh_gives_one_line_error(tmp_path, name):
    path = tmp_path / name
    path.write_text(BAD_OBJS[name])
    _assert_one_line_error(run("render", str(path), "-o", str(tmp_path / "x.png")))


@pytest.mark.parametrize("args", [
    ("render", "c50", "--size", "0x0"),
    ("render", "c50", "--size", "banana"),
    ("render", "no-such-scene"),
    ("render", "/no/such/file.obj"),
    ("verilog", "no-such-block", "-o", "x.v"),
])
def test_bad_arguments_give_one_line_error(tmp_path, args):
    _assert_one_line_error(run(*args, cwd=tmp_path))


def test_help_answers():
    r = run("--help")
    assert r.returncode == 0 and "render" in r.stdout and "report" in r.stdout


def test_verilog_list_and_generate(tmp_path):
    r = run("verilog", "--list")
    assert r.returncode == 0 and {"pixelbus", "zbm-chip", "zbm-unit"} <= set(r.stdout.split())
    out = tmp_path / "bank.v"
    r = run("verilog", "pixelbus-bank", "-p", "depth=16", "-o", str(out))
    assert r.returncode == 0, r.stderr
    assert "module pixelbus_bank" in out.read_text()


def _registered_archs():
    from rasterhw.sim import registry

    return sorted(registry.archs())


@pytest.mark.parametrize("arch", _registered_archs())
def test_render_every_registered_arch(tmp_path, arch):
    """Every machine's golden arch renders through the CLI and covers the reference's pixels
    (an arch that drew nothing or the wrong frame size would fail here)."""
    import numpy as np
    from PIL import Image

    out, ref = tmp_path / f"{arch}.png", tmp_path / "ref.png"
    r = run("render", "c50", "--size", "64x64", "--arch", arch, "--json", "-o", str(out))
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout)
    assert res["arch"] == arch and (res["width"], res["height"]) == (64, 64) and res["pixels_written"] > 0
    assert run("render", "c50", "--size", "64x64", "-o", str(ref)).returncode == 0
    a = np.asarray(Image.open(out).convert("RGB")).any(axis=2)
    b = np.asarray(Image.open(ref).convert("RGB")).any(axis=2)
    assert a.shape == (64, 64) and (a & b).sum() >= 0.5 * b.sum()


def test_option_of_another_arch_is_refused():
    r = run("render", "c50", "--size", "32x32", "--arch", "reference", "--interleave", "2")
    assert r.returncode == 2 and r.stderr.strip() == "error: --interleave does not apply to --arch reference"


def test_typed_block_parameters(tmp_path):
    r = run("verilog", "zbm-unit", "--interleave", "1", "-p", "width=16", "-p", "height=8", "-p", "head=maybe",
            "-o", str(tmp_path / "t.v"))
    assert r.returncode == 2 and "true or false" in r.stderr and not (tmp_path / "t.v").exists()
    r = run("verilog", "zbm-unit", "--interleave", "2", "-p", "interleave=1", "-o", str(tmp_path / "t.v"))
    assert r.returncode == 2 and "contradicts" in r.stderr


def test_machines_lists_every_machine():
    r = run("machines")
    assert r.returncode == 0
    for name in ("snu", "zbm"):
        assert name in r.stdout


def test_sim_image_name_carries_the_options_given():
    """Two configurations of one scene (e.g. --schedule paper / overlap) get two default images."""
    from pathlib import Path

    from rasterhw.sim.cli.main import sim_image_name

    a = sim_image_name("c300", "zbm", "verilator", {"interleave": 8, "schedule": "paper", "units": None})
    b = sim_image_name("c300", "zbm", "verilator", {"interleave": 8, "schedule": "overlap", "units": None})
    assert a == Path("out/c300-zbm-verilator-interleave-8-schedule-paper.png") and a != b
    assert sim_image_name("x/scene.obj", "pixelbus", "pysim", {}) == Path("out/scene-pixelbus-pysim.png")


def test_every_json_option_and_every_option_has_help():
    """`--help` answers: every option of every command says what it does (`--json` included)."""
    import click
    from rasterhw.sim.cli.main import cli

    missing = []

    def walk(cmd, path):
        if isinstance(cmd, click.Group):
            for name, sub in cmd.commands.items():
                walk(sub, [*path, name])
            return
        for p in cmd.params:
            if isinstance(p, click.Option) and not p.help and "--help" not in p.opts:
                missing.append(f"{' '.join(path)} {p.opts[0]}")
    walk(cli, ["rasterhw"])
    assert not missing, missing


def test_render_json_has_pixels_covered_for_every_arch(tmp_path):
    """Every arch's render says how many pixels it covered, and it is the reference's (coverage
    is the one thing every machine must agree on)."""
    from rasterhw.sim import registry

    ref = json.loads(run("render", "c50", "--size", "64x64", "--json", "-o", str(tmp_path / "r.png")).stdout)
    for arch in registry.archs():
        r = run("render", "c50", "--size", "64x64", "--arch", arch, "--json", "-o", str(tmp_path / f"{arch}.png"))
        assert r.returncode == 0, (arch, r.stderr[-500:])
        assert json.loads(r.stdout)["pixels_covered"] == ref["pixels_covered"], arch


def test_sim_block_help_lists_only_that_blocks_options():
    """``rasterhw sim BLOCK --help`` shows BLOCK's options and no other block's (issue 46); an option
    of another block is still refused by name, not as an unknown option."""
    from rasterhw.sim import registry

    blocks = registry.sim_blocks()
    for name, (_machine, b) in blocks.items():
        r = run("sim", name, "--help")
        assert r.returncode == 0, r.stderr
        own = {o.flag for o in b.options}
        others = {o.flag for _, (_, x) in blocks.items() for o in x.options} - own
        for flag in own:
            assert f"  {flag} " in r.stdout, (name, flag)
        for flag in others:
            assert f"  {flag} " not in r.stdout and f"{flag}/" not in r.stdout, (name, flag)
    r = run("sim", "pixelbus", "--interleave", "2", "--engine", "pysim")
    assert r.returncode == 2 and r.stderr.strip() == "error: --interleave does not apply to sim pixelbus", r.stderr


def test_engine_names_are_one_list():
    """The command line's --engine choices are registry.ENGINES, every one an engine of sim/engines/."""
    from rasterhw.sim import engines, registry
    from rasterhw.sim.cli.main import cli

    assert set(registry.ENGINES) <= {*engines.ENGINES, *engines.ALIASES}
    for cmd in ("sim", "report", "demo"):
        (opt,) = [p for p in cli.commands[cmd].params if p.name == "engine"]
        assert tuple(opt.type.choices) == registry.ENGINES, cmd


def test_readme_machine_table_is_the_registry():
    """The README's machine table names every registered machine once, with its folder and seed number."""
    import re
    from pathlib import Path

    from rasterhw.sim import registry

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    rows = [ln for ln in text.split("\n| machine (paper")[1].split("\n\n")[0].splitlines()[2:] if ln.startswith("|")]
    folders = {}
    for ln in rows:
        cells = [c.strip() for c in ln.strip("|").split("|")]
        folders[cells[1].strip("`")] = re.search(r"seed (\d{3})", cells[0]).group(1)
    assert folders == {m.name: m.seed[:3] for m in registry.machines().values()}
