"""``workdirs._child_pids``: the kernel's list of this process's children, which lets
``end_descendants`` skip psutil when nothing is below the command, holds every child psutil
sees: one started from another thread, and an orphan given to this process as a subreaper."""

import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc children lists: Linux")

CHILDREN = """
import subprocess, threading, time, psutil
from rasterhw.sim import workdirs as w
assert w._child_pids() == [], w._child_pids()
assert w.end_descendants() == 0
a = subprocess.Popen(['sleep', '30'])
box = []
t = threading.Thread(target=lambda: box.append(subprocess.Popen(['sleep', '30'])))
t.start(); t.join()
w.become_subreaper()
subprocess.run(['sh', '-c', 'sleep 30 & exit 0'], check=True)
time.sleep(0.3)
kids = sorted(w._child_pids())
assert len(kids) == 3 and kids == sorted(k.pid for k in psutil.Process().children()), kids
assert w.end_descendants() == 3
assert w._child_pids() == []
"""

NO_CHILD = """
import sys
from rasterhw.sim import workdirs as w
assert w.end_descendants() == 0
print('psutil' in sys.modules)
"""


def _python(code: str) -> str:
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_the_kernel_list_holds_what_psutil_sees():
    _python(CHILDREN)


def test_no_child_means_no_psutil_import():
    assert _python(NO_CHILD).split() == ["False"]
