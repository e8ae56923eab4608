"""What the build cache holds, and pruning it: the library of ``rasterhw cache info|clean``
(``sim/cli/cache.py``) and of the size cap after a run (``RASTERHW_CACHE_MAX``).

The cache folder (``sim/paths.py: BUILD_ROOT``) is a set of *entries*: each top-level folder or
file, except in the folders that hold many entries (``sim/cachefile.py: NESTED``: generated
Verilog texts one file each, Verilator runtime objects and gcc profiles one folder each, the task
store one result each). :func:`entries` says of each its ``kind`` (:data:`KINDS`, from its name),
the ``design`` it is of, its ``size_bytes`` (disk use, as ``du`` counts it) and ``last_use``: the
newest modification time of anything in it, which every cache hit moves (``cachefile.mark_used``),
so an entry built long ago and run every day is not "old".

:func:`clean` removes entries, least recently used first: those last used longer ago than
``older_than`` seconds, then as many as it takes to bring the cache to at most ``max_size`` bytes.
It never removes an entry in use: one whose build lock (``NAME.lock`` beside it, the ``filelock``
library of ``sim/workdirs.py: build_lock``) another process holds, one holding a run folder of a
process still running (``workdirs.temp_run_folder`` names its process), or the work folder of a
build in progress. The entry is removed while this process holds its lock, so a build that starts
meanwhile waits and then builds afresh. Lock files stay (they take no disk space; removing a lock
file another process has open would let two holders in).
"""

from __future__ import annotations

import os
import re
import shutil
import stat
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cachefile import NESTED, RECORD_SUFFIX
from rasterhw.sim.workdirs import host_tag

__all__ = ["KINDS", "CAP_ENV", "Entry", "apply_cap", "cap_from_env", "clean", "entries", "parse_age",
           "parse_size"]

#: the environment variable of the size cap applied after every command (:func:`apply_cap`)
CAP_ENV = "RASTERHW_CACHE_MAX"

#: the import closures kept beside the generated Verilog (``verilog_cache.closure_cached``):
#: ``verilog/design-sources-<digest>.json`` (a block's), ``bench-sources-`` (a bench's roots,
#: ``engines/verilator.py``), ``model-sources-`` (a golden array's); of no one design
_SOURCE_INDEX = r"^(design|bench|model)-sources-[0-9a-f]+\.json$"
#: (pattern on an entry's name, kind): the first that matches names the kind; a folder of
#: :data:`~rasterhw.sim.cachefile.NESTED` gives its entries' kind by the folder's name, except the
#: import closures among the generated Verilog (:data:`_SOURCE_INDEX`)
KINDS: tuple[tuple[str, str], ...] = (
    (r"^tb-.*-cocotb-(verilator|icarus)-[0-9a-f]+$", "cocotb-build"),
    (r"^tb-.*-pgogen-", "pgo-training-build"),
    (r"^tb-", "verilator-build"),
    (r"^mut-", "mutation-build"),
    (r"^mutate-", "mutation"),
    (r"^synth-", "synthesis"),
    (r"^prove-", "proof"),
    (r"^pnr-", "place-and-route"),
    (r"^.+-(verilator|icarus)-[0-9a-f]{10}$", "cocotb-build"),
)
_NESTED_KIND = {"verilog": "verilog", "zbm-verilog": "verilog", "verilator-runtime": "verilator-runtime",
                "pgo": "pgo-profile", "tasks": "task-result"}
#: what the name of an entry says besides its design (removed to name the design)
_AFFIXES = (r"^(tb|mut|mutate|synth|prove|pnr-ecp5|pnr-ice40|pnr)-", r"-[0-9a-f]{10,16}(\.v|\.json)?$",
            r"-trace-(vcd|fst)$", r"-hier$", r"-pgo(gen)?$", r"-cocotb$", r"-(verilator|icarus)$")
_HOST = host_tag()
#: a run folder (``workdirs.temp_run_folder``) and a build's work folder (``workdirs.work_folder``)
#: carry the host and the process that made them
_RUN = re.compile(r"^run-(?P<host>[A-Za-z0-9]+)-(?P<pid>\d+)-")
_WORK = re.compile(r"^\.(?P<name>.+)\.tmp-(?P<host>[A-Za-z0-9]+)-(?P<pid>\d+)-[^-]*$")

_UNITS = {"": 1, "b": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
_AGES = {"s": 1, "m": 60, "h": 3600, "d": 86400, "w": 7 * 86400}


@dataclass
class Entry:
    """One entry of the cache (see the module docstring)."""

    path: Path
    kind: str
    design: str | None
    size_bytes: int
    last_use: float              # seconds since the epoch
    in_use: str | None = None    # why it must not be removed now (None: it may be)

    def to_json(self, root: Path) -> dict:
        d = asdict(self)
        d["path"] = str(self.path.relative_to(root))
        d["last_use"] = time.strftime("%Y-%m-%dT%H:%M:%S%z", time.localtime(self.last_use))
        d["last_use_age_s"] = round(max(0.0, time.time() - self.last_use), 1)
        return d


# ------------------------------------------------------------------ input
def parse_size(text: str, what: str = "--max-size") -> int:
    """``"100M"``, ``"1.5G"``, ``"500k"``, ``"200MB"``, ``"4096"`` (bytes; K, M, G, T are powers of
    1024) -> bytes; anything else is a one-line :class:`RasterhwError`."""
    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([kmgt]?)(i?b)?\s*", str(text), re.I)
    if m is None or (m.group(3) and not m.group(2) and m.group(3).lower() != "b"):
        raise RasterhwError(f"{what} must be a size such as 100M, 2G or 500K (bytes; K/M/G/T are 1024-based), "
                            f"not {text!r}")
    return int(float(m.group(1)) * _UNITS[m.group(2).lower()])


def parse_age(text: str, what: str = "--older-than") -> float:
    """``"7d"``, ``"12h"``, ``"30m"``, ``"90s"``, ``"2w"`` (a bare number is days) -> seconds; anything
    else is a one-line :class:`RasterhwError`."""
    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([smhdw]?)\s*", str(text), re.I)
    if m is None:
        raise RasterhwError(f"{what} must be an age such as 7d, 12h, 30m, 90s or 2w, not {text!r}")
    return float(m.group(1)) * _AGES[(m.group(2) or "d").lower()]


def cap_from_env() -> int | None:
    """The size cap :data:`CAP_ENV` sets (bytes), None if unset or empty; a bad value is a one-line error."""
    text = os.environ.get(CAP_ENV, "").strip()
    return parse_size(text, CAP_ENV) if text else None


# ------------------------------------------------------------------ what is there
def _walk(path: Path) -> tuple[int, float]:
    """(disk use in bytes, newest modification time) of ``path`` and everything under it (links not followed)."""
    try:
        st = path.lstat()
    except OSError:
        return 0, 0.0
    size, newest = st.st_blocks * 512, st.st_mtime
    if stat.S_ISDIR(st.st_mode):
        try:
            with os.scandir(path) as it:
                kids = list(it)
        except OSError:
            kids = []
        for k in kids:
            s, t = _walk(Path(k.path))
            size += s
            newest = max(newest, t)
    return size, newest


def _alive(host: str, pid: str) -> bool:
    import psutil

    return host != _HOST or psutil.pid_exists(int(pid))   # another host's process: assume it runs


def _kind(name: str, nested: str | None) -> str:
    if nested is not None:
        return "source-index" if re.search(_SOURCE_INDEX, name) else _NESTED_KIND[nested]
    for pat, kind in KINDS:
        if re.search(pat, name):
            return kind
    return "other"


def _design(path: Path, kind: str) -> str | None:
    if kind == "task-result":   # the task's own name: the file starts {"task": {"kind": ..., "name": ...
        try:
            with open(path, "rb") as f:
                head = f.read(400).decode("utf-8", "replace")
        except OSError:
            return None
        m = re.search(r'"name": "([^"]+)"', head)
        return m.group(1) if m else None
    if kind in ("verilator-runtime", "source-index", "other"):
        return None
    name = path.name
    build = path / "build.json"
    if build.is_file():   # a Verilator build records its model
        import json

        try:
            name = str(json.loads(build.read_text())["model"])
        except (OSError, ValueError, KeyError):
            pass
    for a in _AFFIXES:
        name = re.sub(a, "", name)
    for a in _AFFIXES[2:]:   # -pgo-trace-vcd and the like: every suffix, in any order
        name = re.sub(a, "", name)
    return name or None


def _in_use(path: Path, root: Path) -> str | None:
    """Why ``path`` must not be removed now, or None."""
    lock = path.with_name(path.name + ".lock")
    if lock.exists():
        from filelock import FileLock, Timeout

        fl = FileLock(lock)
        try:
            fl.acquire(timeout=0)
        except Timeout:
            return "its build lock is held"
        except OSError:
            pass
        else:
            fl.release()
    if path.is_dir():
        try:
            names = os.listdir(path)
        except OSError:
            names = []
        for n in names:
            m = _RUN.match(n)
            if m and _alive(m["host"], m["pid"]):
                return f"process {m['pid']} runs in it"
    for w in path.parent.glob(f".{path.name}.tmp-*"):
        m = _WORK.match(w.name)
        if m and _alive(m["host"], m["pid"]):
            return f"process {m['pid']} is building it"
    return None


def entries(root: str | Path | None = None, *, check_use: bool = True) -> list[Entry]:
    """Every entry of the cache folder ``root`` (default ``BUILD_ROOT``), least recently used
    first. Lock files, SHA-256 records (counted with their entry) and builds' work folders (a build
    in progress: its process's own; ``workdirs.remove_dead_work_folders`` removes dead ones) are
    not entries. ``check_use``: say of each whether it is in use now (:func:`clean` needs it)."""
    from rasterhw.sim.paths import BUILD_ROOT

    root = Path(root if root is not None else BUILD_ROOT)
    if not root.is_dir():
        return []
    out = []

    def add(path: Path, nested: str | None) -> None:
        size, newest = _walk(path)
        rec = path.with_name(path.name + RECORD_SUFFIX)
        if path.is_file() and rec.is_file():
            s, t = _walk(rec)
            size, newest = size + s, max(newest, t)
        kind = _kind(path.name, nested)
        out.append(Entry(path, kind, _design(path, kind), size, newest,
                         _in_use(path, root) if check_use else None))

    for p in sorted(root.iterdir()):
        name = p.name
        if name.endswith((".lock", RECORD_SUFFIX)) or _WORK.match(name) or name.startswith(".rasterhw-writable-"):
            continue
        depth = NESTED.get(name, 0) if p.is_dir() else 0
        if not depth:
            add(p, None)
            continue
        level = [p]
        for _ in range(depth):
            level = [c for d in level if d.is_dir() for c in sorted(d.iterdir())]
        for c in level:
            if c.name.endswith((".lock", RECORD_SUFFIX)) or c.name.startswith(".") or _WORK.match(c.name):
                continue
            add(c, name)
    return sorted(out, key=lambda e: e.last_use)


def total_bytes(root: str | Path | None = None) -> int:
    """Disk use of the whole cache folder (entries, lock files, work folders: what ``du`` says)."""
    from rasterhw.sim.paths import BUILD_ROOT

    return _walk(Path(root if root is not None else BUILD_ROOT))[0]


# ------------------------------------------------------------------ pruning
def _remove(e: Entry) -> bool:
    """Remove entry ``e`` under its build lock (if it has one); False if it came into use meanwhile."""
    lock = e.path.with_name(e.path.name + ".lock")
    held = None
    if lock.exists():
        from filelock import FileLock, Timeout

        held = FileLock(lock)
        try:
            held.acquire(timeout=0)
        except Timeout:
            return False
    try:
        if e.path.is_dir() and not e.path.is_symlink():
            shutil.rmtree(e.path, ignore_errors=True)
        else:
            e.path.unlink(missing_ok=True)
        e.path.with_name(e.path.name + RECORD_SUFFIX).unlink(missing_ok=True)
    finally:
        if held is not None:
            held.release()
    return not e.path.exists()


def clean(root: str | Path | None = None, *, older_than: float | None = None, max_size: int | None = None,
          dry_run: bool = False) -> dict:
    """Remove entries (see the module docstring): last used more than ``older_than`` seconds ago,
    then least recently used first until the cache takes at most ``max_size`` bytes. Returns
    ``{"removed": [entry JSON], "removed_bytes", "kept_in_use": [entry JSON], "total_bytes"
    (after), "max_size_bytes", "over_cap"}`` (``over_cap``: entries in use alone keep it above
    ``max_size``)."""
    from rasterhw.sim.paths import BUILD_ROOT
    from rasterhw.sim.workdirs import remove_dead_work_folders

    root = Path(root if root is not None else BUILD_ROOT)
    if not root.is_dir():
        return {"removed": [], "removed_bytes": 0, "kept_in_use": [], "total_bytes": 0,
                "max_size_bytes": max_size, "over_cap": False}
    if not dry_run:
        remove_dead_work_folders(root)
    all_entries = entries(root)
    total = total_bytes(root)
    now = time.time()
    removed, busy = [], []
    for e in all_entries:   # least recently used first
        old = older_than is not None and now - e.last_use > older_than
        big = max_size is not None and total > max_size
        if not (old or big):
            continue
        if e.in_use:
            busy.append(e)
            continue
        if dry_run or _remove(e):
            removed.append(e)
            total -= e.size_bytes
        else:
            e.in_use = "its build lock was taken while cleaning"
            busy.append(e)
    if not dry_run:
        total = total_bytes(root)
    return {"removed": [e.to_json(root) for e in removed], "removed_bytes": sum(e.size_bytes for e in removed),
            "kept_in_use": [e.to_json(root) for e in busy], "total_bytes": total, "max_size_bytes": max_size,
            "over_cap": max_size is not None and total > max_size}


def apply_cap() -> dict | None:
    """Prune the cache to :data:`CAP_ENV` (if set) after a command: what :func:`clean` did, or None."""
    cap = cap_from_env()
    if cap is None:
        return None
    return clean(max_size=cap)
