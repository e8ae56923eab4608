"""Waves on request: ``rasterhw sim BLOCK ... --waves out.vcd`` (never on by default), with a
GTKWave save file ``out.gtkw`` beside it and an optional window of cycles
(``--trace-start N --trace-end M``).

:func:`recording` wraps one simulation run:

* ``--engine pysim``: every Amaranth ``Simulator`` the run creates writes its trace with
  ``Simulator.write_vcd`` (VCD; pysim writes no FST) through :class:`VcdWindow`, which adds a
  cycle counter (``rasterhw.cycle``: the clock's rising edges from 0). A run with several
  simulators (one per line or per chip) writes ``out.vcd``, ``out.1.vcd``, ...;
* ``--engine verilator`` / ``icarus`` on a cocotb bench: ``WAVES=1`` for the run (cocotb's
  runner builds with tracing: VCD from Verilator's ``--trace``, the bench's own dump from
  Icarus), and the trace the run wrote is copied to the path given (its suffix must match);
* ``--engine verilator`` on a plain-Verilator scene run (ZB/M unit, EXPERTS PXP, sparse video
  processors, the SNU pixel-bus frame): the model is built once more with ``--trace-fst`` (or
  ``--trace`` for a ``.vcd`` name; its own build folder, so the untraced model stays as it is) and
  the shared C++ main writes the trace to the path given (``+waves=``, the window as
  ``+trace_start=`` / ``+trace_end=``). A run of several binaries (one per processor of the sparse
  matrix) writes ``out.fst``, ``out.1.fst``, ... in the order the runs started.

The window counts clock edges from 0 at the first rising edge of the run (the testbenches'
convention, ``sim/testbench.py``) and keeps edges ``start .. end - 1``: the Verilator main opens
the trace at edge ``start`` (all values, then changes) and closes it at edge ``end``; pysim
cannot start ``write_vcd`` once time has advanced, so its VCD goes through :class:`VcdWindow`,
which keeps the header, writes every value at the window's first time step and then only the
changes inside the window (the edges are those of the trace's ``clk``). A cocotb bench's VCD is
cut the same way after the run.

Every trace gets a save file from :func:`write_gtkw`: its header is read with wellen
(``pywellen``, the parser Surfer uses; VCD and FST), and the save file shows the clock, the reset
and a cycle counter (the compiled bench's ``cycles``, or the one added to a pysim trace), then
the stream ports of the block (Amaranth names a port's members ``PORT__valid``,
``PORT__ready``, ``PORT__payload``, in pysim and in the generated Verilog alike) in the
shallowest scope that has any, one GTKWave group per port, a payload whose structure an engine
declared (:func:`declare_payloads`) split into its fields; zoomed to the whole trace, with the
dump path relative to the save file. Names GTKWave cannot read are said on stderr
(:func:`gtkwave_unreadable`); the generated Verilog has none (``sim/engines/verilog.py:
yosys_init_renamed``). Shared code knows no machine: the names are the block's own.

Open the file with Surfer (``surfer out.vcd``, or drop it on https://app.surfer-project.org)
or GTKWave (``gtkwave out.gtkw``, or ``gtkwave out.fst``); see ``docs/architecture.md#waves``.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import os
import re
import shutil
import subprocess
import threading
import time
import weakref
from collections.abc import Iterator
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.paths import BUILD_ROOT, env_set

__all__ = ["VcdWindow", "amaranth_hook_ok", "check_window", "declare_streams", "next_plain_trace",
           "plain_trace_format", "recording", "vcd_header", "write_gtkw"]

_lock = threading.Lock()
#: while a ``recording`` of a compiled run is open: ``{"path": Path, "written": [Path, ...], "window": (s, e)}``
_plain: dict | None = None
#: stream ports a pysim engine declared for its simulator: ``{Simulator: {port name: interface}}``
_streams: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


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


def next_plain_trace() -> list[str]:
    """The plus-arguments of the next plain-Verilator run's trace (``[]``: waves are off): the file it
    writes (``+waves=``: ``out.fst``, then ``out.1.fst``, ``out.2.fst``, ...; thread-safe: the sparse
    matrix runs its processors in threads) and the window's edges (``+trace_start=`` / ``+trace_end=``)."""
    with _lock:
        if _plain is None:
            return []
        path, written, (start, end) = _plain["path"], _plain["written"], _plain["window"]
        written.append(_nth(path, len(written)))
    # the binary runs in its run folder: a relative name would land (and vanish) there
    return [f"+waves={written[-1].absolute()}", *([f"+trace_start={start}"] if start else []),
            *([f"+trace_end={end}"] if end is not None else [])]


def _nth(path: Path, n: int) -> Path:
    return path if n == 0 else path.with_suffix(f".{n}{path.suffix}")


def declare_streams(sim, streams: dict) -> None:
    """Say which stream ports (``{name: interface}``) simulator ``sim`` drives and collects: with
    ``--waves`` its GTKWave save file shows one group per port (Amaranth writes it)."""
    _streams[sim] = dict(streams)
    declare_payloads(streams)


def check_window(start: int | None, end: int | None, *, waves: object = True) -> tuple[int, int | None]:
    """``(start, end)`` of a trace window given on the command line, checked (one-line errors)."""
    if start is None and end is None:
        return 0, None
    if waves is None:
        raise RasterhwError("--trace-start / --trace-end need --waves FILE")
    for flag, v in (("--trace-start", start), ("--trace-end", end)):
        if v is not None and (isinstance(v, bool) or not isinstance(v, int) or v < 0):
            raise RasterhwError(f"{flag} must be a cycle number 0 or more, not {v!r}")
    s = start or 0
    if end is not None and end <= s:
        raise RasterhwError(f"--trace-end {end} must be after --trace-start {s}")
    return s, end


# ---------------------------------------------------------------------------------------- VCD
class VcdWindow:
    """A text file to write a VCD into that keeps only clock edges ``start .. end - 1``.

    The header goes through as it is; the clock is the header's first ``clk`` variable (the
    shallowest), and an edge is a change of it to 1. The first time step inside the window gets
    every variable's current value (``$dumpvars``), later ones their changes; nothing after edge
    ``end`` is written. ``name`` and :meth:`tell` are those of the file written (Amaranth's GTKWave
    writer reads them)."""

    def __init__(self, out, start: int, end: int | None, clock: str = "clk", *, counter: bool = False):
        self.out, self.start, self.end, self.clock = out, start, end, clock
        self.counter = counter    # add ``rasterhw.cycle``: the clock edges counted from 0
        self._ids: set[str] = set()
        self._cid: str | None = None
        self.name = getattr(out, "name", "")
        self._buf = ""
        self._header = True
        self._clk: str | None = None
        self._clk_val = "0"
        self._last: dict[str, str] = {}
        self._t: int | None = None
        self._block: list[tuple[str, str]] = []
        self.edges = 0            # rising clock edges so far
        self.opened = False       # the window's first time step is written
        self._written = 0

    # file protocol (what pyvcd's writer and print() use)
    def write(self, s: str) -> int:
        if "\n" not in s:
            self._buf += s
            return len(s)
        *lines, rest = (self._buf + s).split("\n")
        self._buf = rest
        for ln in lines:
            self._line(ln)
        return len(s)

    def tell(self) -> int:
        return self._written

    def flush(self) -> None:
        self.out.flush()

    def close(self) -> None:
        if self._buf:
            self._line(self._buf)
            self._buf = ""
        self._finish_block()
        if self._clk is None:
            raise RasterhwError(f"--trace-start/--trace-end: {self.name} has no {self.clock!r} clock to count")
        self.out.close()

    def _emit(self, text: str) -> None:
        self.out.write(text)
        self._written += len(text)

    def _line(self, ln: str) -> None:
        if self._header and self.counter and "$enddefinitions" in ln.split():
            self._cid = next(c for k in range(len(self._ids) + 1) if (c := f"rhw{k}") not in self._ids)
            self._emit(f"$scope module rasterhw $end\n$var wire 32 {self._cid} cycle [31:0] $end\n$upscope $end\n")
        if self._header:
            self._emit(ln + "\n")
            tok = ln.split()
            if tok[:1] == ["$var"] and len(tok) >= 5:
                self._ids.add(tok[3])
                if self._clk is None and tok[4].lstrip("\\") == self.clock:
                    self._clk = tok[3]
            if "$enddefinitions" in tok:
                self._header = False
            return
        if not ln:
            return
        if ln[0] == "#":
            self._finish_block()
            self._t = int(ln[1:])
            return
        if ln[0] == "$":          # $dumpvars / $end / $comment ...: we write our own $dumpvars
            return
        if ln[0] in "bBrRsS":
            ident = ln.split(None, 1)[1].strip()
        else:
            ident = ln[1:].strip()
        self._block.append((ident, ln))

    def _finish_block(self) -> None:
        if self._t is None:
            return
        rose = False
        for ident, ln in self._block:
            self._last[ident] = ln
            if ident == self._clk:
                v = ln[0]
                if v == "1" and self._clk_val != "1":
                    self.edges += 1
                    rose = True
                self._clk_val = v
        if self._cid is not None and rose:   # the edge's number, from 0 at the first
            ln = f"b{self.edges - 1:b} {self._cid}"
            self._last[self._cid] = ln
            self._block.append((self._cid, ln))
        c = self.edges              # rising edges at or before this time step
        inside = c >= self.start + 1 and (self.end is None or c <= self.end)
        if inside:
            if not self.opened:
                self.opened = True
                self._emit(f"#{self._t}\n$dumpvars\n" + "".join(v + "\n" for v in self._last.values()) + "$end\n")
            else:
                self._emit(f"#{self._t}\n" + "".join(ln + "\n" for _, ln in self._block))
        self._block = []
        self._t = None


def vcd_header(path: Path) -> list[tuple[tuple[str, ...], str, int, str, str]]:
    """Every variable a trace (VCD or FST) declares: ``(scope path, name, width, bit range, signal)``,
    read with wellen (``pywellen``, the parser Surfer uses) from the header alone. ``bit range`` is
    ``[width-1:0]`` for a vector (what GTKWave appends to a vector's name; Amaranth's Verilog and
    pysim number every vector from 0), ``""`` for one bit; ``signal`` is the same string for every
    variable that names the same net (a module port and the bench wire it is connected to)."""
    import pywellen

    try:
        w = pywellen.Waveform(str(path), multi_threaded=False, stream_only=True)
    except Exception as e:   # pywellen raises its own exception types (and OSError) with one line
        raise RasterhwError(f"{path}: not a trace wellen can read: {str(e).splitlines()[0] if str(e) else e!r}") from None
    out = []

    def walk(scopes, above):
        for sc in scopes:
            here = (*above, sc.name)
            for v in sc.vars():
                width = v.bitwidth or 1
                out.append((here, v.name, width, f"[{width - 1}:0]" if width > 1 else "", str(v.signal_ref)))
            walk(sc.scopes(), here)

    walk(w.scopes(), ())
    return out


def gtkwave_unreadable(vars_) -> list[str]:
    """The variables of :func:`vcd_header` whose names GTKWave's VCD reader rejects ("$VAR parse
    error"): a ``:`` in a name (GTKWave 3.3.118 reads it as the start of a bit range; Yosys's
    ``$auto$verilog_backend.cc:N:dump_module$K`` registers had one, issue 53)."""
    return [".".join((*s, n)) for s, n, *_ in vars_ if ":" in re.sub(r"\[\d+:\d+\]$", "", n)]


_STREAM = re.compile(r"^\\?(?P<port>[A-Za-z_][A-Za-z0-9_]*?)__(?P<member>valid|ready|payload)(?P<rest>(\.[^$]*)?)$")
_ORDER = {"valid": 0, "ready": 1, "payload": 2}


def stream_signals(vars_) -> tuple[tuple[str, ...], dict[str, list[str]]]:
    """The stream ports of the block in a VCD header (from :func:`vcd_header`): the shallowest scope
    with ``PORT__valid`` variables and, per port, its signals as GTKWave names (``scope.name`` and
    the bit range of a vector). Where the scope's parent shares nets with some of those ports (a
    Verilog module's ports are the nets its bench drives), only those are kept: the block's own
    wires that happen to be named like a stream (a sub-block's port) are left out."""
    hits = [(s, n, w, r, i, m) for s, n, w, r, i in vars_ if (m := _STREAM.match(n))]
    scopes = [s for s, *_, m in hits if m["member"] == "valid"]
    if not scopes:
        return (), {}
    top = min(scopes, key=len)
    parent_ids = {i for s, *_, i in vars_ if s == top[:-1]}
    ports: dict[str, list[tuple[int, str, str]]] = {}
    wired: set[str] = set()
    for s, n, _w, r, i, m in hits:
        if s != top:
            continue
        ports.setdefault(m["port"], []).append((_ORDER[m["member"]], m["rest"], ".".join((*s, n)) + r))
        if i in parent_ids:
            wired.add(m["port"])
    # the ports an engine declared (:func:`declare_payloads`): pysim's trace has no bench scope
    # above the block, so its sub-blocks' ports look like the block's own
    declared = _declared & set(ports)
    return top, {p: [name for *_, name in sorted(sig, key=lambda t: (t[0], t[1]))]
                 for p, sig in ports.items() if (not wired or p in wired) and (not declared or p in declared)}


def _shallowest(vars_, name: str, scope: tuple[str, ...] = ()) -> str | None:
    """GTKWave name of the shallowest variable called ``name`` (inside ``scope`` if one is given
    and has it), or None."""
    got = [(len(s), k, ".".join((*s, n)) + r) for k, (s, n, w, r, i) in enumerate(vars_)
           if n == name and s[:len(scope)] == scope]
    if not got and scope:
        return _shallowest(vars_, name)
    return min(got)[2] if got else None


#: payload fields of the stream ports the engines declared (:func:`declare_payloads`), by port
#: name: ``[(field, lsb, width), ...]`` (nested structures as dotted names, leaves only)
_payloads: dict[str, list[tuple[str, int, int]]] = {}
#: the stream ports the engines declared, as the trace names them (``o_merge[0]`` -> ``o_merge__0``)
_declared: set[str] = set()


def payload_fields(shape) -> list[tuple[str, int, int]]:
    """Leaf fields ``(dotted name, lsb, width)`` of a payload shape (a ``data.Layout`` /
    ``data.Struct``; an array layout's elements named by index); ``[]`` for a plain value."""
    from amaranth.hdl import Shape
    from amaranth.lib import data

    try:
        lay = data.Layout.cast(shape)
    except TypeError:
        return []
    out = []
    for name, f in lay:
        sub = payload_fields(f.shape)
        if sub:
            out += [(f"{name}.{n}", f.offset + lsb, w) for n, lsb, w in sub]
        else:
            out.append((str(name), f.offset, Shape.cast(f.shape).width))
    return out


def declare_payloads(ports: dict) -> None:
    """Say what the payload of each stream port (``{name: interface}``) is made of: the GTKWave
    save file splits a payload the trace holds as one vector (an input port's, on pysim and on
    Verilator alike) into these fields."""
    for name, port in ports.items():
        traced = name.replace("[", "__").replace("]", "").replace(".", "__")
        _declared.add(traced)
        payload = getattr(port, "payload", None)
        shape = getattr(payload, "shape", None)
        fields = payload_fields(shape()) if callable(shape) else []
        if fields:
            _payloads[traced] = fields


#: GTKWave's window on a trace: the save file asks for this size and fits the trace into the
#: wave area (about the width less the signal list)
GTKW_SIZE = (1400, 800)
_WAVE_PX = 1100


def fit_zoom(t0: int, t1: int, px: int = _WAVE_PX) -> float:
    """GTKWave's zoom (``*Z`` line of a save file) that shows time ``t0 .. t1`` in ``px`` pixels:
    one pixel is ``2**-Z`` time units of the trace."""
    import math

    return -math.ceil(math.log2(max(t1 - t0, 1) / px))


def _time_span(path: Path) -> tuple[int, int] | None:
    """First and last time step of a VCD (the first ``#T`` after the header, the last in the
    file's tail); None for an FST or a trace with no time step."""
    if path.suffix != ".vcd":
        return None
    first = last = None
    with open(path, "rb") as f:
        for ln in f:
            if ln.startswith(b"#") and ln[1:].strip().isdigit():
                first = int(ln[1:])
                break
        if first is None:
            return None
        f.seek(max(0, f.seek(0, 2) - (1 << 16)))
        for ln in f.read().splitlines():
            if ln.startswith(b"#") and ln[1:].strip().isdigit():
                last = int(ln[1:])
    return first, max(first, last or first)


def write_gtkw(vcd: Path, gtkw: Path | None = None) -> Path:
    """A GTKWave save file beside ``vcd`` (``out.vcd`` -> ``out.gtkw``) that opens the trace with
    its clock, reset and cycle counter, then the block's stream ports (:func:`stream_signals`),
    one group per port, a payload held as one vector split into its fields
    (:func:`declare_payloads`), zoomed to show the whole trace. The dump path is relative to the
    save file (GTKWave takes it so when ``[savefile]`` is relative too): the pair can be moved."""
    import sys

    from vcd.gtkw import GTKWSave

    vcd, gtkw = Path(vcd), Path(gtkw) if gtkw else Path(vcd).with_suffix(".gtkw")
    vars_ = vcd_header(vcd)
    bad = gtkwave_unreadable(vars_)
    if bad:
        print(f"warning: {vcd}: {len(bad)} name(s) GTKWave cannot read (first: {bad[0]})", file=sys.stderr)
    top, ports = stream_signals(vars_)
    clk = _shallowest(vars_, "clk", top[:-1])
    rst = _shallowest(vars_, "rst", top[:-1])
    # the cycle counter: the one this module adds to a pysim trace (:class:`VcdWindow`), else
    # the compiled bench's own ``cycles`` beside its clock
    cycle = _shallowest(vars_, "cycle", ("rasterhw",)) if any(s == ("rasterhw",) for s, *_ in vars_) else None
    if cycle is None and clk is not None:
        cyc = [".".join((*s, n)) + r for s, n, w, r, i in vars_ if n == "cycles" and len(s) == 1
               and ".".join(s) == clk.rsplit(".", 1)[0]]
        cycle = cyc[0] if cyc else None
    span = _time_span(vcd)
    with open(gtkw, "w") as f:
        g = GTKWSave(f)
        g.comment(f"rasterhw: {'.'.join(top) or 'the trace'}: clock, reset, cycle counter and stream ports")
        g.dumpfile(os.path.relpath(vcd.absolute(), gtkw.absolute().parent), abspath=False)
        g.savefile(gtkw.name, abspath=False)
        g.size(*GTKW_SIZE)
        if span is not None:   # zoomed to fit the whole trace
            g.timestart(span[0])
            g.zoom_markers(fit_zoom(*span), span[0])
        for k in range(1, len(top) + 1):
            g.treeopen(".".join(top[:k]))
        for name, fmt in ((clk, "bin"), (rst, "bin"), (cycle, "dec")):
            if name is not None:
                g.trace(name, datafmt=fmt)
        for port, names in ports.items():
            fields = _payloads.get(port)
            with g.group(port):
                for n in names:
                    m = re.search(r"__payload\[(\d+):0\]$", n)
                    if fields and not m and "__payload." in n:
                        continue   # a field the trace holds itself: shown from the payload below
                    g.trace(n)
                    if fields and m:
                        # GTKWave's combined trace: bits of the one payload vector, (k) counted
                        # from its MSB (GTKWave does not find Verilator's dotted field names)
                        width = int(m.group(1)) + 1
                        for field, lsb, w in fields:
                            if lsb + w <= width:
                                bits = " ".join(f"({width - 1 - b}){n}" for b in range(lsb + w - 1, lsb - 1, -1))
                                f.write(f"#{{{n[:m.start()]}__payload.{field}[{w - 1}:0]}} {bits}\n")
    return gtkw


# ---------------------------------------------------------------------------------- pysim hook
#: what the hook was written against: Amaranth 0.5's ``Simulator.run(self)`` and
#: ``Simulator.write_vcd(self, vcd_file, gtkw_file=None, *, traces=(), fs_per_delta=0)``
_AMARANTH_RUN = ["self"]
_AMARANTH_WRITE_VCD = ["self", "vcd_file", "gtkw_file", "traces", "fs_per_delta"]


def amaranth_hook_ok() -> str | None:
    """``None`` if Amaranth's simulator is the one the pysim hook was written for (0.5, ``run`` and
    ``write_vcd`` as above), else why not. Amaranth has no public way to trace every simulator a
    run creates (the scene drivers make their own), so :func:`recording` wraps ``Simulator.run``
    for the run's duration; ``tests/test_library_hooks.py`` fails when this stops holding."""
    import amaranth
    from amaranth.sim import Simulator

    ver = getattr(amaranth, "__version__", "?")
    if not ver.startswith("0.5."):
        return f"Amaranth {ver} (the waves hook is written for 0.5)"
    for fn, want in ((Simulator.run, _AMARANTH_RUN), (Simulator.write_vcd, _AMARANTH_WRITE_VCD)):
        got = list(inspect.signature(fn).parameters)
        if got != want:
            return f"Amaranth {ver}: Simulator.{fn.__name__}{tuple(got)} (the waves hook expects {tuple(want)})"
    return None


@contextlib.contextmanager
def _pysim(path: Path, window: tuple[int, int | None]) -> Iterator[list[Path]]:
    from amaranth.sim import Simulator

    why = amaranth_hook_ok()
    if why:
        raise RasterhwError(f"--waves on pysim: {why}")
    written: list[Path] = []
    windows: list[VcdWindow] = []
    orig = Simulator.run

    def run(self):
        out = _nth(path, len(written))
        written.append(out)
        streams = _streams.get(self)
        # every trace goes through the window filter (the whole run when no window was asked
        # for), which adds the cycle counter; the save file is ours (:func:`write_gtkw`)
        vcd_file = VcdWindow(open(out, "w"), *window, counter=True)   # noqa: SIM115 - closed below
        windows.append(vcd_file)
        try:
            with self.write_vcd(vcd_file, traces=streams or ()):
                return orig(self)
        finally:
            vcd_file.close()

    Simulator.run = run
    try:
        yield written
    finally:
        Simulator.run = orig
    if window != (0, None) and windows and not any(w.opened for w in windows):
        # (a run of several simulators, one per line or chip: one that ended before the window
        # keeps a trace with its header only, as long as another reached it)
        raise RasterhwError(f"--trace-start {window[0]}: the run ended after {max(w.edges for w in windows)} cycles")
    for out in written:
        write_gtkw(out)


@contextlib.contextmanager
def recording(path: str | Path | None, engine: str, *, start: int | None = None,
              end: int | None = None) -> Iterator[list[Path]]:
    """Record the waves of the simulation run inside the ``with`` to ``path`` (``None``: off),
    only clock edges ``start .. end - 1`` if given, with a GTKWave save file beside every VCD."""
    window = check_window(start, end, waves=path)
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
    _payloads.clear()
    _declared.clear()
    if engine == "pysim":
        with _pysim(path, window) as written:
            yield written
        if not written:
            raise RasterhwError("--waves: this run started no Amaranth simulation")
        return
    global _plain
    t0 = time.time()
    written: list[Path] = []
    with _lock:
        _plain = {"path": path, "written": written, "window": window}
    try:
        with env_set("WAVES", "1"):
            yield written
    finally:
        with _lock:
            _plain = None
    if written:  # plain-Verilator runs wrote their traces where they were told
        missing = [p for p in written if not p.exists()]
        if missing and window[0] and len(missing) < len(written):
            # several binaries (one per processor): one that ended before the window wrote nothing
            written[:] = [p for p in written if p.exists()]
        elif missing:
            if window[0]:
                raise RasterhwError(f"--trace-start {window[0]}: the run ended before that cycle "
                                    f"(no trace written to {missing[0]})")
            raise RasterhwError(f"--waves: the run wrote no trace to {missing[0]}")
        for p in written:
            write_gtkw(p)   # VCD or FST: wellen reads both, and so does GTKWave
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
    if window != (0, None):
        if path.suffix != ".vcd":
            raise RasterhwError(f"--waves {path}: a trace window on a cocotb bench needs a .vcd trace")
        w = VcdWindow(open(path, "w"), *window)  # noqa: SIM115 - closed by w.close()
        with open(newest) as f:
            shutil.copyfileobj(f, w)
        w.close()
        if not w.opened:
            raise RasterhwError(f"--trace-start {window[0]}: the run ended after {w.edges} cycles")
    else:
        shutil.copyfile(newest, path)
    write_gtkw(path)
    written.append(path)
