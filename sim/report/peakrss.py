"""``python -m rasterhw.sim.report.peakrss FILE CMD...``: run CMD, then write to FILE the largest resident
set (MB) of CMD and every descendant it waited for (``RUSAGE_CHILDREN``; for ``make`` that is the
biggest compiler process), and exit with CMD's status. Used by the Verilator builds to print
their compiler memory peak."""

from __future__ import annotations

import resource
import signal
import sys
from pathlib import Path

from rasterhw.sim.workdirs import run_child


def _terminate(signum, _frame):
    raise SystemExit(128 + signum)


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print("usage: python -m rasterhw.sim.report.peakrss FILE CMD...", file=sys.stderr)
        return 2
    # a child of ours, not a plain subprocess.call: its whole tree ends with us (killed with this
    # process by the kernel if we are; on SIGTERM/SIGINT every process below it: sim/workdirs.py)
    signal.signal(signal.SIGTERM, _terminate)
    rc = run_child(argv[1:]).returncode
    peak_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    Path(argv[0]).write_text(f"{peak_kb / 1024:.1f}\n")
    return rc


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
