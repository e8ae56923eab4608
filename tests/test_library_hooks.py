"""The two places we reach into a library's private part, each with a version check that these
tests hold (issue 30 item 6): they fail when Amaranth or cocotb change under us, so the hook is
looked at again (and replaced by a public API if one has come)."""

from __future__ import annotations

import inspect

import pytest


def test_amaranth_is_the_version_the_pysim_waves_hook_was_written_for():
    """``sim/engines/waves.py`` wraps ``Simulator.run`` for a ``--waves`` run (Amaranth has no
    public way to trace every simulator a run creates) and calls ``write_vcd(gtkw_file=, traces=)``."""
    from amaranth.sim import Simulator
    from rasterhw.sim.engines import waves

    assert waves.amaranth_hook_ok() is None
    # run() is the loop over advance() the hook wraps (run_until / advance are not wrapped)
    assert "self.advance()" in inspect.getsource(Simulator.run)


def test_cocotb_is_the_version_the_runner_hook_was_written_for(tmp_path):
    """``sim/engines/runner.py: child_runner`` overrides ``Runner._execute_cmds`` in a subclass: the
    one method through which cocotb's ``build`` and ``test`` start processes."""
    from cocotb_tools.runner import Runner, Verilator
    from rasterhw.sim.engines import runner

    assert runner.cocotb_hook_ok() is None
    src = inspect.getsource(Runner._execute)
    assert "self._execute_cmds(" in src and "subprocess" not in src
    assert "subprocess.run" in inspect.getsource(Runner._execute_cmds)
    r = runner.child_runner("verilator")
    assert isinstance(r, Verilator) and type(r) is not Verilator
    assert type(r)._execute_cmds is runner._execute_cmds_as_children
    assert type(runner.child_runner("verilator")) is type(r)     # one subclass per runner class
    r.env = {}
    r._execute_cmds([["true"]], cwd=str(tmp_path))
    with pytest.raises(RuntimeError, match="return code: 3"):
        r._execute_cmds([["sh", "-c", "exit 3"]], cwd=str(tmp_path))
