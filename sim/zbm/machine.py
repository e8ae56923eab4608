"""Registry entry of the ZB/M scan-line Z-buffer merger (seed 003)."""

from rasterhw.sim.registry import Arch, Machine, Option, SimBlock

_INTERLEAVE = Option("interleave", "ZB/M chips per scan line (1, 2, 4, 8 or 16)", default=8, type=int)
_UNITS = Option("units", "ZB/M units chained by merge ports", default=1, type=int)
_SCHEDULE = Option("schedule", "ZB/M timing: overlap (ours) or paper (sec. 6.1's schedule)", default="overlap",
                   choices=("overlap", "paper"))

MACHINE = Machine(
    name="zbm",
    title="ZB/M scan-line Z-buffer merger (Matsushita)",
    seed="003_3355a922071bd992.txt",
    archs=(Arch("zbm", "ZB/M bit-accurate model: edge pairs, segment generator, double Z, merge, composite",
                "rasterhw.golden_model.zbm.render:render_scene", options=(_INTERLEAVE, _UNITS)),),
    blocks={"zbm-chip": "rasterhw.hdl.zbm.chip:ZbmChip",
            "zbm-seggen": "rasterhw.hdl.zbm.seggen:ZbmSegmentGenerator",
            "zbm-unit": "rasterhw.hdl.zbm.unit:ZbmUnit",
            # parts of the chip, for synth / fpga / prove (sim/zbm/blocks.py)
            "zbm-loop": "rasterhw.sim.zbm.blocks:loop",
            "zbm-merger": "rasterhw.sim.zbm.blocks:merger",
            "zbm-pixel": "rasterhw.sim.zbm.blocks:pixel"},
    sims=(SimBlock("zbm", "the scene's edge pairs through a ZB/M unit (segment generator + chips) in HDL",
                   "rasterhw.sim.zbm.scene_run:simulate_zbm", default_scene="c300", options=(_INTERLEAVE, _UNITS, _SCHEDULE)),),
    report="rasterhw.sim.zbm.report:rows",
    bench="rasterhw.sim.zbm.bench:bench",
    soak={"zbm": "rasterhw.sim.zbm.soak:zbm_round"},
    proofs={"zbm-merger": "rasterhw.sim.zbm.proof:PROOF"},
    status="segment generator, ZB/M chip (8 pixel processors on a segment loop, double Z, merger on its own "
           "clock), unit, chained units (HDL, bit- and cycle-exact)",
)
