"""The i860 XR's on-chip data cache as a timing model: set-associative, LRU, write-back, a line fill
over the external bus on a load miss.

Facts and where they come from (:data:`CACHE_PARAMETERS`; none is taken from a paper's table):

* DS (*i860 64-bit Microprocessor* data sheet, Intel 1989, order no. 240296; its feature list):
  "8 Kbyte Data Cache", "128-Bit Internal Data Cache Bus", "64-Bit External Data Bus".
* PRM (*i860 64-bit Microprocessor Programmer's Reference Manual*, Intel 1989, order no. 240329),
  the chapter on caching, and Kohn & Margulis, "Introducing the Intel i860 64-bit
  microprocessor", IEEE Micro 9(4), 1989: two-way set associative, 32-byte lines, write-back.
  These three facts are as we read them there; this module was written without the manual open
  (no copy here), so each is marked "recalled" in :data:`CACHE_PARAMETERS`.
* The miss cost is the line fill alone: 32 bytes over the 64-bit bus = 4 bus cycles of 2 clocks
  (the pipelined bus, ``I860.bus_clocks_per_cycle``) = 8 clocks, the least a board can take; the
  board of ZB/M's table 2 is not named, so its memory's wait states are not known (a lower bound).
* Stores: a store that hits updates the line (dirty; written back when the line is evicted, one
  line write of the same cost); a store that misses does not fetch the line (no write-allocate,
  our reading) and goes to the bus through the write buffer, not charged here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["CACHE_PARAMETERS", "DataCache"]

#: every parameter of :class:`DataCache`: field -> (default, source)
CACHE_PARAMETERS: dict[str, tuple[object, str]] = {
    "size_bytes": (8192, "DS feature list: '8 Kbyte Data Cache'"),
    "line_bytes": (32, "PRM, caching chapter; Kohn & Margulis 1989: 32-byte lines (recalled)"),
    "ways": (2, "PRM, caching chapter; Kohn & Margulis 1989: two-way set associative (recalled)"),
    "write_back": (True, "PRM, caching chapter; Kohn & Margulis 1989: write-back (recalled)"),
    "write_allocate": (False, "our reading: a store miss does not fetch the line (not charged)"),
    "miss_clocks": (8, "line / DS 64-bit bus = 4 bus cycles x 2 clocks (DS: pipelined bus); board wait "
                       "states unknown, so a lower bound"),
}


@dataclass
class DataCache:
    """An LRU set-associative data cache; :meth:`access` one byte address at a time."""

    size_bytes: int = 8192
    line_bytes: int = 32
    ways: int = 2
    write_back: bool = True
    write_allocate: bool = False
    miss_clocks: int = 8
    hits: int = 0
    misses: int = 0
    writebacks: int = 0
    store_misses: int = 0
    _sets: list = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        for name in ("size_bytes", "line_bytes", "ways", "miss_clocks"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise RasterhwError(f"data cache: {name} must be a positive integer, not {v!r}")
        if self.size_bytes % (self.line_bytes * self.ways):
            raise RasterhwError("data cache: size must be a multiple of line x ways")
        self._sets = [[] for _ in range(self.size_bytes // (self.line_bytes * self.ways))]  # [tag, dirty], MRU last

    def access(self, addr: int, *, store: bool = False) -> None:
        line = addr // self.line_bytes
        ways = self._sets[line % len(self._sets)]
        for i, (tag, _dirty) in enumerate(ways):
            if tag == line:
                self.hits += 1
                ways.append([tag, ways.pop(i)[1] or (store and self.write_back)])
                return
        if store and not self.write_allocate:
            self.store_misses += 1
            return
        self.misses += 1
        if len(ways) == self.ways:
            if ways.pop(0)[1]:
                self.writebacks += 1
        ways.append([line, store and self.write_back])

    @property
    def stall_clocks(self) -> int:
        """Clocks the processor waits: a line fill per load miss, a line write per dirty eviction."""
        return (self.misses + self.writebacks) * self.miss_clocks
