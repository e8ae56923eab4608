"""Where a test run's CPU goes (opt-in: ``RASTERHW_TEST_CPULOG=FILE``): every test appends one JSON
line to FILE with its CPU seconds (user + sys of the pytest process and of the child processes it
waited for: simulators, compilers, Yosys) from its setup to its teardown, its wall seconds, when it
ended (``end``, Unix time: a build folder's ``built`` time then says which test paid for the build)
and the worker's pid. CPU is what the suite costs whatever else runs on the machine (wall time is not: on
a loaded machine it grows with the load), so the sum over tests is the run's worker-CPU; a child
process that outlives its test (a Dask cluster kept for the session) is counted in the test that
reaps it. Used for docs/speed.md's account of the suite."""

from __future__ import annotations

import json
import os
import resource
import time

import pytest


def _cpu() -> float:
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return s.ru_utime + s.ru_stime + c.ru_utime + c.ru_stime


class CpuLog:
    def __init__(self, path: str):
        self.path = path

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_protocol(self, item, nextitem):
        t, c = time.perf_counter(), _cpu()
        yield
        with open(self.path, "a") as fh:
            fh.write(json.dumps({"test": item.nodeid, "cpu_s": round(_cpu() - c, 3),
                                 "wall_s": round(time.perf_counter() - t, 3), "end": round(time.time(), 1),
                                 "pid": os.getpid()}) + "\n")
