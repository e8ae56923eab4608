"""Registry entry of EXPERTS (seed 000): its arch, report and bench (no HDL block yet)."""

from rasterhw.sim.registry import Arch, Machine, Option

MACHINE = Machine(
    name="experts",
    title="EXPERTS scan-line multiprocessor (Kyoto Univ.)",
    seed="000_5ac5e14b809e6e93.txt",
    archs=(Arch("experts", "EXPERTS scan-line golden model: SLP (Y-sort, X-merge, L-sort, ASL) and PXP "
                "(span cull, depth search, smooth shading, anti-jagging) stages",
                "rasterhw.golden_model.experts.render:render",
                options=(Option("aj", "anti-jagging alpha: none, (a) area, (b) perpendicular distance, "
                                "(c) along/across the scan line (EXPERTS)", "c", ("none", "a", "b", "c")),
                         Option("model", "float (ideal arithmetic) or bit (16-bit hardware formats)", "bit",
                                ("float", "bit")),
                         Option("sn", "SLPs (bands of scan lines) for the timing stats", 8, type=int),
                         Option("pn", "PXPs per SLP (ranges of each line) for the timing stats", 8, type=int))),),
    report="rasterhw.sim.experts.report:rows",
    bench="rasterhw.sim.experts.bench:bench",
    status="scan-line golden model split as SLP/PXP (float and 16-bit), Sn x Pn parallel model with "
           "load balancing at both levels, fig. 4.1 cost model (golden; no HDL yet)",
)
