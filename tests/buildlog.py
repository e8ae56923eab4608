"""Where a test run's build time goes (opt-in: ``RASTERHW_TEST_BUILDLOG=FILE``): every Verilator build
and every Verilog conversion that takes over 0.3 s is appended to FILE as one JSON line with its
seconds, the test that caused it (``PYTEST_CURRENT_TEST``) and the worker's pid. Used for
docs/speed.md's account of a fresh run."""

from __future__ import annotations

import functools
import importlib
import json
import os
import time

#: (module, function) pairs timed; ``verilator.convert_cached`` is the name that module imported
TIMED = (("rasterhw.sim.engines.runner", "_build_plain_in", "build"),
         ("rasterhw.sim.engines.verilog_cache", "convert_cached", "convert"),
         ("rasterhw.sim.engines.verilator", "convert_cached", "convert"),
         ("zbm_cocotb.unit_verilog", "convert_cached", "convert"))


def install(path: str) -> None:
    for mod_name, name, kind in TIMED:
        mod = importlib.import_module(mod_name)
        f = getattr(mod, name)

        @functools.wraps(f)
        def timed(*a, _f=f, _kind=kind, **k):
            t = time.perf_counter()
            try:
                return _f(*a, **k)
            finally:
                s = time.perf_counter() - t
                if s > 0.3:
                    with open(path, "a") as fh:
                        fh.write(json.dumps({"kind": _kind, "s": round(s, 2), "what": str(a[0])[-60:] if a else "",
                                             "test": os.environ.get("PYTEST_CURRENT_TEST", ""),
                                             "pid": os.getpid()}) + "\n")
        setattr(mod, name, timed)
