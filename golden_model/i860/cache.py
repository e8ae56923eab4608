"""The i860 XR's on-chip data cache as a timing model: set-associative, LRU, write-back, a line fill
over the external bus on a load miss.

Facts and where they come from (:data:`CACHE_PARAMETERS`; none is taken from a paper's table):

* DS (*i860 64-bit Microprocessor* data sheet, Intel 1989, order no. 240296; the feature list of its
  first page, read at docslib.org/doc/11958439): "8 Kbyte Data Cache", "128-Bit Internal Data Cache
  Bus", "64-Bit External Data Bus".
* PRM (*i860 64-bit Microprocessor Programmer's Reference Manual*, Intel 1989, order no. 240329),
  §5.13 "Cache flush", p. 5-21 (read in the scan at manualslib.com/manual/1203080, titled there
  "Intel i86W Manual", its page 83): "There are two 32-byte blocks in the cache which can be
  replaced by the address #const + isrc2" (two-way set associative, 32-byte lines: the XP's caches
  are four-way, so this is the XR's manual); "The flush instruction is used to force modified data
  in the data cache to external memory" and "Cache elements containing modified data are written
  back to memory" (write-back: modified lines stay in the cache until replaced or flushed).
* The miss cost is *chosen*, not cited: neither the manual pages found nor the data sheet's feature
  list give the clocks of a line fill, and the board of ZB/M's table 2 is not named, so its
  memory's wait states are not known. We take the line fill alone at the bus's best: 32 bytes over
  the 64-bit bus = 4 bus cycles of 2 clocks (the pipelined bus, ``I860.bus_clocks_per_cycle``) =
  8 clocks, a lower bound. ``rasterhw report zbm`` prints table 2's polygons/s with it varied
  (rows "table 2 (cache sensitivity)": 8 ... 40 clocks).
* Stores: a store that hits updates the line (dirty; written back when the line is evicted, one
  line write of the same cost); a store that misses does not fetch the line (no write-allocate,
  our reading) and goes to the bus through the write buffer, not charged here.
* Replacement: least recently used within a set (our choice; the manual pages found name only the
  RB field of ``dirbase`` choosing the block a ``flush`` replaces). On ZB/M's streaming records it
  barely matters: one way instead of two changes the stalls by about 1 clock per polygon.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["CACHE_PARAMETERS", "DataCache"]

#: every parameter of :class:`DataCache`: field -> (default, source)
CACHE_PARAMETERS: dict[str, tuple[object, str]] = {
    "size_bytes": (8192, "DS, feature list of its first page: '8 Kbyte Data Cache' (also Intel's comp.sys.intel "
                         "posting of the data sheet, 1989-03-04: '8K Byte Data Cache')"),
    "line_bytes": (32, "PRM §5.13 'Cache flush', p. 5-21: 'There are two 32-byte blocks in the cache which can be "
                       "replaced by the address'"),
    "ways": (2, "PRM §5.13, p. 5-21: 'two 32-byte blocks in the cache which can be replaced' by one address "
                "(two-way set associative)"),
    "write_back": (True, "PRM §5.13, p. 5-21: 'The flush instruction is used to force modified data in the data "
                         "cache to external memory'; 'Cache elements containing modified data are written back to "
                         "memory'"),
    "write_allocate": (False, "chosen (our reading): a store miss does not fetch the line (not charged); the "
                              "ZB/M report prints table 2 with it on"),
    "miss_clocks": (8, "chosen: a lower bound, line / DS 64-bit bus = 4 bus cycles x 2 clocks (pipelined bus); the "
                       "manual pages found give no fill time and the board's wait states are unknown; the ZB/M "
                       "report prints table 2 at 8-40 clocks"),
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
