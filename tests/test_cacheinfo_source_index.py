"""``rasterhw cache info`` names the import closures kept beside the generated Verilog
(``build/verilog/{design,bench,model}-sources-<digest>.json``, ``verilog_cache.closure_cached``) as
what they are, of no design, not as Verilog of a design called ``bench-sources``."""

from __future__ import annotations

import json

from rasterhw.sim import cacheinfo
from rasterhw.sim.cachefile import write_entry


def test_the_import_closures_are_source_indexes_of_no_design(tmp_path):
    root = tmp_path / "cache"
    for name in ("design-sources-09ae1d16f08bf98e.json", "bench-sources-9ea4c18c09a4ca7f.json",
                 "model-sources-0123456789abcdef.json"):
        write_entry(root / "verilog" / name, json.dumps(["rasterhw/hdl/experts/slp.py"]).encode(), root=root)
    write_entry(root / "verilog" / "experts-slp-0123456789abcdef.v", b"module top; endmodule\n", root=root)
    got = sorted((e.path.name, e.kind, e.design) for e in cacheinfo.entries(root, check_use=False))
    assert got == [("bench-sources-9ea4c18c09a4ca7f.json", "source-index", None),
                   ("design-sources-09ae1d16f08bf98e.json", "source-index", None),
                   ("experts-slp-0123456789abcdef.v", "verilog", "experts-slp"),
                   ("model-sources-0123456789abcdef.json", "source-index", None)]
