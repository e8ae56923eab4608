"""The build lock (``sim/workdirs.py: build_lock``) on the ``filelock`` library: the second of two
processes that build one folder says it waits and gets the lock once the first lets go; the
command line imports where there is no ``fcntl`` (Windows)."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time

HOLD = textwrap.dedent("""
    import sys, time
    from rasterhw.sim.workdirs import build_lock
    with build_lock(sys.argv[1], what="model-x"):
        print(f"got {time.time()}", flush=True)
        time.sleep(float(sys.argv[2]))
        print(f"free {time.time()}", flush=True)
""")


def _start(folder, hold: float) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-c", HOLD, str(folder), str(hold)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_second_process_waits_with_a_message_then_builds(tmp_path):
    folder = tmp_path / "model-x"
    first = _start(folder, 2.0)
    assert first.stdout.readline().startswith("got ")     # the first holds the lock
    second = _start(folder, 0.0)
    out1, err1 = first.communicate(timeout=60)
    out2, err2 = second.communicate(timeout=60)
    assert first.returncode == 0 and second.returncode == 0, (err1, err2)
    free1 = float(out1.split()[-1])
    got2 = float(out2.split()[1])
    assert got2 >= free1                                  # the second waited for the first
    assert "waiting for another build of model-x to finish" in err2
    assert "waiting" not in err1                          # no message when the lock is free
    assert (tmp_path / "model-x.lock").exists() or not any(tmp_path.glob("*.lock"))


def test_lock_is_reentrant_in_one_process(tmp_path):
    from rasterhw.sim.workdirs import build_lock

    t0 = time.time()
    with build_lock(tmp_path / "m"), build_lock(tmp_path / "m"):
        pass
    assert time.time() - t0 < 5


def test_cli_imports_without_fcntl(tmp_path):
    """Windows has no ``fcntl``: the command line still imports and the lock still works."""
    code = ("import sys, warnings; sys.modules['fcntl'] = None; warnings.simplefilter('ignore')\n"
            "import rasterhw.sim.cli.main\nfrom rasterhw.sim.workdirs import build_lock\n"
            f"with build_lock({str(tmp_path / 'm')!r}): print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
