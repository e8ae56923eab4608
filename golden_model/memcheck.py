"""Memory estimates checked before a large frame is allocated.

A frame too big for the machine should end in one line naming the size and what it needs,
not in the kernel's out-of-memory kill (exit 137, no message) minutes later. Callers
estimate what they will allocate (bytes per pixel times pixels, plus a constant) and call
:func:`check_memory` first.

What is available: ``MemAvailable`` from ``/proc/meminfo``, lowered to the cgroup's limit
(``memory.max`` minus ``memory.current``) when the process runs in one; the environment
variable ``RASTERHW_MEMORY_LIMIT`` (bytes, or with a K/M/G suffix) overrides both, which
tests use to check the error without allocating gigabytes.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["available_bytes", "check_memory", "format_bytes", "parse_bytes"]

#: fraction of the available memory one command may plan to use
HEADROOM = 0.85
_SUFFIX = {"": 1, "K": 1 << 10, "M": 1 << 20, "G": 1 << 30, "T": 1 << 40}


def parse_bytes(text: str) -> int:
    """``"512M"`` -> 536870912; a plain integer is bytes."""
    m = re.fullmatch(r"\s*([0-9]+(?:\.[0-9]*)?)\s*([KMGT]?)(?:I?B)?\s*", text.upper())
    if m is None:
        raise RasterhwError(f"RASTERHW_MEMORY_LIMIT must be bytes like 4G or 512M, not {text!r}")
    return int(float(m.group(1)) * _SUFFIX[m.group(2)])


def format_bytes(n: float) -> str:
    for unit, size in (("GB", 1 << 30), ("MB", 1 << 20), ("kB", 1 << 10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} B"


def _cgroup_free() -> int | None:
    root = Path("/sys/fs/cgroup")
    try:
        limit = (root / "memory.max").read_text().strip()
        if limit == "max":
            return None
        return int(limit) - int((root / "memory.current").read_text())
    except (OSError, ValueError):
        return None


def available_bytes() -> int:
    """Bytes this process can still allocate without swapping (best estimate; see module)."""
    override = os.environ.get("RASTERHW_MEMORY_LIMIT")
    if override:
        return parse_bytes(override)
    avail = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                avail = int(line.split()[1]) * 1024
                break
    except (OSError, ValueError, IndexError):
        pass
    if avail is None:
        try:
            avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (OSError, ValueError):
            return 1 << 62  # cannot tell: do not refuse
    cg = _cgroup_free()
    return min(avail, cg) if cg is not None else avail


def check_memory(need: int, what: str) -> None:
    """Raise :class:`RasterhwError` if ``need`` bytes do not fit in the available memory
    (with :data:`HEADROOM`). ``what`` names the job, e.g. ``"render 16384x16384 (zbm)"``."""
    avail = available_bytes()
    if need > HEADROOM * avail:
        raise RasterhwError(f"{what} needs about {format_bytes(need)} of memory, "
                            f"{format_bytes(avail)} is available; use a smaller --size")
