"""A package like any other: the wheel built from this checkout, installed without the checkout,
runs a Verilator scene run from an empty folder with its caches in an empty cache folder."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
import zipfile
from pathlib import Path

import pytest
from rasterhw.sim.engines.runner import OPT_ENV
from rasterhw.sim.engines.vlruntime import cache_dir

ROOT = Path(__file__).resolve().parents[1]


#: a module left in setuptools' old build folder of the checkout (as a moved module was): never shipped
STALE = ROOT / "build" / "lib" / "rasterhw" / "sim" / "zz_stale_module.py"


def _build_wheel(src: Path, out: Path) -> tuple[Path, str]:
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "-v", "--no-deps", "-w", str(out), str(src)],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, (r.stdout + r.stderr)[-2000:]
    (whl,) = out.glob("rasterhw-*.whl")
    return whl, r.stdout + r.stderr


@pytest.fixture(scope="module")
def built(tmp_path_factory) -> tuple[Path, str]:
    planted = not STALE.exists()
    STALE.parent.mkdir(parents=True, exist_ok=True)
    STALE.write_text("raise ImportError('a stale module of an old build folder')\n")
    try:
        return _build_wheel(ROOT, tmp_path_factory.mktemp("wheel"))
    finally:
        if planted:
            STALE.unlink()


@pytest.fixture(scope="module")
def wheel(built) -> Path:
    return built[0]


def test_the_build_is_quiet_and_versioned_and_ships_nothing_stale(built):
    """Every shipped folder is a declared package (no setuptools warning that one is absent from the
    packages configuration); the build folder is not the checkout's build/ (the cache): a module
    left there is not shipped; the wheel is named and stamped with sim/version.py's version."""
    from rasterhw.sim.version import version

    whl, log = built
    assert "is absent from the `packages` configuration" not in log and "Package would be ignored" not in log
    names = zipfile.ZipFile(whl).namelist()
    assert not any("zz_stale_module" in n for n in names)
    assert whl.name.startswith(f"rasterhw-{version()}-")
    stamp = zipfile.ZipFile(whl).read("rasterhw/_version.py").decode()
    assert f'VERSION = "{version()}"' in stamp


@pytest.mark.heavy
def test_a_wheel_from_a_tarball_without_git_has_the_release(tmp_path):
    """A source tree without .git (git archive, as a release tarball): the wheel builds, its version
    is the release alone."""
    from rasterhw import __version__

    if not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    src = tmp_path / "src"
    src.mkdir()
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", "--format=tar", "HEAD"], capture_output=True,
                         check=True, timeout=120).stdout
    subprocess.run(["tar", "-x", "-C", str(src)], input=tar, check=True, timeout=120)
    whl, log = _build_wheel(src, tmp_path / "out")
    assert whl.name.startswith(f"rasterhw-{__version__}-py3"), whl.name
    assert f'VERSION = "{__version__}"' in zipfile.ZipFile(whl).read("rasterhw/_version.py").decode()


def test_the_wheel_carries_benches_and_templates_and_nothing_of_the_checkout(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    for need in ("rasterhw/cocotb_tests/harness.v", "rasterhw/cocotb_tests/plain_main.cpp",
                 "rasterhw/cocotb_tests/xorshift.vh", "rasterhw/sim/report/templates/index.html.j2",
                 "rasterhw/golden_model/vzbuf/paper_tables.csv"):
        assert need in names, need
    # every scene run's bench top is generated (sim/engines/verilator.py): the ZB/M cocotb cross-check
    # of the engines is a test (tests/zbm_cocotb/), not in the wheel
    for gone in ("unit_bench", "chip_bench", "chain_flat", "stimfiles", "unit_verilog", "tb_zbm_unit", "cocotb_zbm"):
        assert not any(gone in n for n in names), gone
    assert any(n.endswith("licenses/LICENSE") for n in names)
    for bad in (".venv/", "/build/", "/out/", "rasterhw/tests/", "__pycache__", "rasterhw/setup.py"):
        assert not any(bad in n for n in names), bad


@pytest.mark.heavy
def test_the_installed_wheel_runs_a_verilator_scene_from_an_empty_folder(wheel, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    site = Path(subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    # the dependencies come from this environment (its site folder on the path, after the wheel's
    # own); this environment's editable install of the checkout is not seen (a .pth line adds a
    # folder, it does not run the folder's own .pth files)
    (site / "deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    r = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "--no-deps",
                        str(wheel)], capture_output=True, text=True, timeout=600)
    if r.returncode and "--python" in r.stderr:   # an older pip: install with the target's own runpy
        r = subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(site),
                            str(wheel)], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-2000:]
    work, cache = tmp_path / "empty", tmp_path / "cache"
    work.mkdir()
    cache.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith(("RASTERHW_", "PYTHONPATH"))}
    env.update(RASTERHW_CACHE=str(cache), PATH=f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}")
    # the model is built in the empty cache; the Verilator runtime's objects (design-independent,
    # keyed by Verilator's version and the flags: sim/engines/vlruntime.py, tested in
    # tests/test_vlruntime.py) and the build level are the test run's, so the wheel does not
    # compile the runtime again (~8 s of a ~16 s test)
    env["RASTERHW_VL_RUNTIME_DIR"] = str(cache_dir("plain", []).parent)
    if OPT_ENV in os.environ:
        env[OPT_ENV] = os.environ[OPT_ENV]
    where = subprocess.run([str(py), "-c", "import rasterhw, sys; print(rasterhw.__file__)"], cwd=work, env=env,
                           capture_output=True, text=True, check=True).stdout.strip()
    assert str(ROOT) not in where and str(site) in where
    from rasterhw.sim.version import version

    shown = subprocess.run([str(py), "-m", "rasterhw.sim.cli.main", "--version"], cwd=work, env=env,
                           capture_output=True, text=True, check=True).stdout
    assert shown == f"rasterhw, version {version()}\n"   # outside the checkout, the commit it was built from
    r = subprocess.run([str(py), "-m", "rasterhw.sim.cli.main", "sim", "pixelbus", "--scene", "snu-100px",
                        "--size", "64x64", "--engine", "verilator", "--json", "-o", "frame.png"],
                       cwd=work, env=env, capture_output=True, text=True, timeout=1800)
    assert r.returncode == 0, r.stderr[-2000:]
    res = json.loads(r.stdout)
    assert res["mismatches"] == 0 and res["pixels_compared"] == 64 * 64
    assert list(cache.glob("tb-pixelbus-*/build.json"))           # the model was built in the cache folder
    assert sorted(p.name for p in work.iterdir()) == ["frame.png"]  # nothing else in the working folder
    assert not any(p.name == "build" for p in Path(where).parent.iterdir())   # none in site-packages
