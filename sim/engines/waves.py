"""Waves on request: ``rasterhw sim BLOCK ... --waves out.vcd`` (never on by default).

:func:`recording` wraps one simulation run:

* ``--engine pysim``: every Amaranth ``Simulator`` the run creates writes its trace with
  ``Simulator.write_vcd`` (VCD; pysim writes no FST). A run with several simulators (one per
  line or per chip) writes ``out.vcd``, ``out.1.vcd``, ...;
* ``--engine verilator`` / ``icarus`` on a cocotb bench: ``WAVES=1`` for the run (cocotb's
  runner builds with tracing: VCD from Verilator's ``--trace``, the bench's own dump from
  Icarus), and the trace the run wrote is copied to the path given (its suffix must match);
* ``--engine verilator`` on a plain-Verilator scene run (ZB/M unit, EXPERTS PXP, sparse video
  processors, the SNU pixel-bus frame): the model is built once more with ``--trace-fst`` (or
  ``--trace`` for a ``.vcd`` name; its own build folder, so the untraced model stays as it is) and
  the shared C++ main writes the trace to the path given (``+waves=``). A run of several binaries
  (one per processor of the sparse matrix) writes ``out.fst``, ``out.1.fst``, ... in the order the
  runs started.

Open the file with Surfer (``surfer out.vcd``, or drop it on https://app.surfer-project.org)
or GTKWave (``gtkwave out.fst``); see ``docs/architecture.md#waves``.
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import subprocess
import threading
import time
from collections.abc import Iterator
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.paths import BUILD_ROOT

__all__ = ["next_plain_trace", "plain_trace_format", "recording"]

_lock = threading.Lock()
#: while a ``recording`` of a compiled run is open: ``{"path": Path, "written": [Path, ...]}``
_plain: dict | None = None


@functools.cache
def fst_writer_available() -> bool:
    """Whether the C++ compiler finds the headers Verilator's FST writer includes (``lz4.h``,
    ``zlib.h``: Debian packages, not on PyPI); VCD needs nothing."""
    src = "#include <lz4.h>\n#include <zlib.h>\n"
    try:
        r = subprocess.run(["c++", "-x", "c++", "-E", "-o", os.devnull, "-"], input=src, text=True,
                           capture_output=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return False
    return r.returncode == 0


def plain_trace_format() -> str | None:
    """``"fst"`` or ``"vcd"`` while waves are being recorded for a compiled run, else ``None``:
    what :func:`rasterhw.sim.engines.runner.build_plain_verilator` builds the model with."""
    with _lock:
        return None if _plain is None else _plain["path"].suffix[1:]


def next_plain_trace() -> Path | None:
    """The file the next plain-Verilator run writes its trace to (``None``: waves are off);
    ``out.fst``, then ``out.1.fst``, ``out.2.fst``, ... (thread-safe: the sparse matrix runs its
    processors in threads)."""
    with _lock:
        if _plain is None:
            return None
        path, written = _plain["path"], _plain["written"]
        out = path if not written else path.with_suffix(f".{len(written)}{path.suffix}")
        written.append(out)
        return out


@contextlib.contextmanager
def _pysim(path: Path) -> Iterator[list[Path]]:
    from amaranth.sim import Simulator

    written: list[Path] = []
    orig = Simulator.run

    def run(self, *a, **kw):
        n = len(written)
        out = path if n == 0 else path.with_suffix(f".{n}{path.suffix}")
        written.append(out)
        with self.write_vcd(str(out)):
            return orig(self, *a, **kw)

    Simulator.run = run
    try:
        yield written
    finally:
        Simulator.run = orig


@contextlib.contextmanager
def recording(path: str | Path | None, engine: str) -> Iterator[list[Path]]:
    """Record the waves of the simulation run inside the ``with`` to ``path`` (``None``: off)."""
    if path is None:
        yield []
        return
    path = Path(path)
    if engine == "pysim" and path.suffix != ".vcd":
        raise RasterhwError(f"--waves {path}: Amaranth pysim writes VCD; name a .vcd file")
    if path.suffix not in (".fst", ".vcd"):
        raise RasterhwError(f"--waves {path}: name a .vcd file (or .fst where Verilator can write FST)")
    if engine != "pysim" and path.suffix == ".fst" and not fst_writer_available():
        raise RasterhwError(f"--waves {path}: Verilator's FST writer needs lz4.h and zlib.h, not installed here "
                            "(Debian: liblz4-dev zlib1g-dev); name a .vcd file")
    path.parent.mkdir(parents=True, exist_ok=True)   # only once the name is good
    if engine == "pysim":
        with _pysim(path) as written:
            yield written
        if not written:
            raise RasterhwError("--waves: this run started no Amaranth simulation")
        return
    global _plain
    t0 = time.time()
    old = os.environ.get("WAVES")
    os.environ["WAVES"] = "1"
    written: list[Path] = []
    with _lock:
        _plain = {"path": path, "written": written}
    try:
        yield written
    finally:
        with _lock:
            _plain = None
        if old is None:
            os.environ.pop("WAVES", None)
        else:
            os.environ["WAVES"] = old
    if written:  # plain-Verilator runs wrote their traces where they were told
        missing = [p for p in written if not p.exists()]
        if missing:
            raise RasterhwError(f"--waves: the run wrote no trace to {missing[0]}")
        return
    # a cocotb bench (WAVES=1): the trace its runner wrote in the build folder
    traces = [p for ext in ("*.fst", "*.vcd") for p in BUILD_ROOT.rglob(ext)
              if p.stat().st_mtime >= t0]
    if not traces:
        raise RasterhwError(f"--waves: the {engine} run of this block wrote no trace")
    newest = max(traces, key=lambda p: p.stat().st_mtime)
    if newest.suffix != path.suffix:
        raise RasterhwError(f"--waves {path}: this bench writes {newest.suffix[1:].upper()}; "
                            f"name a {newest.suffix} file")
    shutil.copyfile(newest, path)
    written.append(path)
