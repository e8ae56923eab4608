"""Waves on request: ``rasterhw sim BLOCK ... --waves out.vcd`` (never on by default).

:func:`recording` wraps one simulation run:

* ``--engine pysim``: every Amaranth ``Simulator`` the run creates writes its trace with
  ``Simulator.write_vcd`` (VCD; pysim writes no FST). A run with several simulators (one per
  line or per chip) writes ``out.vcd``, ``out.1.vcd``, ...;
* ``--engine verilator`` / ``icarus`` on a cocotb bench: ``WAVES=1`` for the run (cocotb's
  runner builds with tracing: FST from Verilator, VCD from Icarus), and the trace the run
  wrote is copied to the path given (its suffix should match: ``.fst`` for Verilator);
* a block whose compiled run is a plain Verilator binary without tracing: one line
  ``error: ...`` saying to use ``--engine pysim``.

Open the file with Surfer (``surfer out.vcd``, or drop it on https://app.surfer-project.org)
or GTKWave (``gtkwave out.fst``); see ``docs/architecture.md#waves``.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import time
from collections.abc import Iterator
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.runner import REPO_ROOT

__all__ = ["recording"]


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
    path.parent.mkdir(parents=True, exist_ok=True)
    if engine == "pysim":
        if path.suffix != ".vcd":
            raise RasterhwError(f"--waves {path}: Amaranth pysim writes VCD; name a .vcd file")
        with _pysim(path) as written:
            yield written
        if not written:
            raise RasterhwError("--waves: this run started no Amaranth simulation")
        return
    t0 = time.time()
    old = os.environ.get("WAVES")
    os.environ["WAVES"] = "1"
    written: list[Path] = []
    try:
        yield written
    finally:
        if old is None:
            os.environ.pop("WAVES", None)
        else:
            os.environ["WAVES"] = old
    traces = [p for ext in ("*.fst", "*.vcd") for p in (REPO_ROOT / "build").rglob(ext)
              if p.stat().st_mtime >= t0]
    if not traces:
        raise RasterhwError(f"--waves: the {engine} run of this block is a plain Verilator binary built "
                            "without tracing; use --engine pysim --waves out.vcd (a smaller scene helps)")
    newest = max(traces, key=lambda p: p.stat().st_mtime)
    shutil.copyfile(newest, path)
    written.append(path)
