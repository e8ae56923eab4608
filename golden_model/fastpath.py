"""A compiled fast path beside the specification it equals bit for bit: which one runs.

Where a golden loop dominates, a numba module stands beside the readable code (the
specification) and gives the same results, bit for bit (``docs/reference.md``, STYLE.md "Fast
paths"). :class:`FastPath` is the one switch they share: the fast module is imported on first use
(importing numba takes ~0.4 s), an environment variable or the caller's ``engine`` picks one, and
where numba cannot be loaded the specification runs, with one line on stderr saying so:

* ``"numba"``: the fast path; an error where numba cannot be loaded;
* the specification's name (``"numpy"`` for the reference rasteriser): the readable code;
* ``None`` / ``"auto"``: the environment variable if set, else numba where it loads.

Users: ``reference.py`` (``reference_fast.py``, ``RASTERHW_REFERENCE``), the sparse machine's
video-processor cycle model (``sparse/vpcycles.py``, ``vpcycles_fast.py``) and the EXPERTS span
PXP's cycle model (``experts/span_cycles_fast.py``, ``RASTERHW_SPANCYCLES``).
"""

from __future__ import annotations

import importlib
import os
import sys
import threading

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["FastPath"]


class FastPath:
    """The engine switch of one fast module.

    Parameters
    ----------
    module : dotted name of the fast module (it imports numba at its top).
    env : environment variable naming the engine when a call does not.
    spec : the specification's engine name (``"numpy"``, ``"python"``).
    fallback : what runs instead, for the stderr line (``"the reference rasteriser runs its NumPy
        specification (same pixels, slower)"``).
    """

    def __init__(self, module: str, *, env: str, spec: str, fallback: str):
        self.module_name, self.env, self.spec, self.fallback = module, env, spec, fallback
        self.engines = ("auto", "numba", spec)
        self._lock = threading.Lock()
        self._mod = None  # the module once loaded, False once it failed to

    def module(self):
        """The fast module, or None where it cannot be loaded; the first failure prints one line
        on stderr."""
        with self._lock:
            if self._mod is None:
                try:
                    self._mod = importlib.import_module(self.module_name)
                except Exception as e:  # ImportError, or numba / llvmlite failing to load
                    self._mod = False
                    why = (str(e).splitlines() or [type(e).__name__])[0]
                    print(f"rasterhw: numba cannot be loaded ({why}); {self.fallback}", file=sys.stderr)
            return self._mod or None

    def choose(self, engine: str | None = None) -> str:
        """``"numba"`` or the specification's name: the engine that runs for ``engine`` (``None``
        = the environment variable, default ``auto``)."""
        want = engine if engine is not None else (os.environ.get(self.env) or "auto")
        if want not in self.engines:
            src = "engine" if engine is not None else self.env
            raise RasterhwError(f"{src} must be one of {', '.join(self.engines)}, not {want!r}")
        if want == self.spec:
            return self.spec
        if self.module() is None:
            if want == "numba":
                raise RasterhwError("the numba engine was asked for, but numba cannot be loaded "
                                    f"(unset {self.env} or set it to {self.spec})")
            return self.spec
        return "numba"
