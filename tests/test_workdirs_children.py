"""``workdirs._child_pids``: the kernel's list of this process's children, which lets
``end_descendants`` skip psutil when nothing is below the command, holds every child psutil
sees: one started from another thread, and an orphan given to this process as a subreaper."""

import subprocess
import sys

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc children lists: Linux")


def test_the_kernel_list_holds_what_psutil_sees():
    code = (
        "import subprocess, threading, time, psutil\n"
        "from rasterhw.sim import workdirs as w\n"
        "assert w._child_pids() == [], w._child_pids()\n"
        "assert w.end_descendants() == 0\n"
        "a = subprocess.Popen(['sleep', '30'])\n"
        "box = []\n"
        "t = threading.Thread(target=lambda: box.append(subprocess.Popen(['sleep', '30'])))\n"
        "t.start(); t.join()\n"
        "w.become_subreaper()\n"
        "subprocess.run(['sh', '-c', 'sleep 30 & exit 0'], check=True)\n"
        "time.sleep(0.3)\n"
        "kids = sorted(w._child_pids())\n"
        "assert len(kids) == 3 and kids == sorted(k.pid for k in psutil.Process().children()), kids\n"
        "assert w.end_descendants() == 3\n"
        "assert w._child_pids() == []\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr


def test_no_child_means_no_psutil_import():
    code = ("import sys\nfrom rasterhw.sim import workdirs as w\n"
            "assert w.end_descendants() == 0\nprint('psutil' in sys.modules)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["False"]

