"""Registry entry of the ZB/M scan-line Z-buffer merger (seed 003)."""

from rasterhw.sim.registry import Arch, Clock, Flow, FpgaSweep, Machine, Option, SimBlock

_INTERLEAVE = Option("interleave", "ZB/M chips per scan line (1, 2, 4, 8 or 16)", default=8, type=int)
_UNITS = Option("units", "ZB/M units chained by merge ports", default=1, type=int)
_SCHEDULE = Option("schedule", "ZB/M timing: overlap (ours) or paper (sec. 6.1's schedule)", default="overlap",
                   choices=("overlap", "paper"))

#: the clocks of sec. 6.1: the segment clock (cond. 3) and the merger's own clock
_SEG = Clock("sync", "ZB/M segment clock 25 MHz (sec. 6.1 cond. 3)", 25e6, "segment clock")
_MERGE = Clock("merge", "ZB/M merge clock: independent of the segment clock, frequency not given", None,
               "merge clock")

MACHINE = Machine(
    headline=("table 1 / 6.1: cycles per edge pair", "6.2: i860s to balance one unit, Gouraud (colour) mode, paper",
              "section 7: chip logic, 2-input gate equivalents (interleave 8, width 512; paper",
              "section 7: chip RAM bits (interleave 8, width 512; paper"),
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
                   "rasterhw.sim.zbm.scene:simulate", default_scene="c300", options=(_INTERLEAVE, _UNITS, _SCHEDULE)),),
    report="rasterhw.sim.zbm.report:rows",
    bench="rasterhw.sim.zbm.bench:bench",
    soak={"zbm": "rasterhw.sim.zbm.soak:zbm_round"},
    proofs={"zbm-merger": "rasterhw.sim.zbm.proof:PROOF"},
    flows={"zbm-chip": Flow(small={"interleave": 8, "width": 128}, fpga={"interleave": 8, "width": 512},
                            fpga_runs=(({"interleave": 8, "width": 512}, "full"),), clocks=(_SEG, _MERGE)),
           "zbm-loop": Flow(small={"interleave": 8, "width": 128}, fpga={"interleave": 8, "width": 512},
                            fpga_runs=(({"interleave": 8, "width": 512}, "full"),), clocks=(_SEG,)),
           "zbm-merger": Flow(small={"fifo_depth": 4}, fpga={"fifo_depth": 16},
                              fpga_runs=(({"fifo_depth": 16}, "full"),), clocks=(_SEG, _MERGE)),
           "zbm-pixel": Flow(small={"interleave": 8, "width": 128}, fpga={"interleave": 8, "width": 512},
                             fpga_runs=(({"interleave": 8, "width": 512}, "full"),), clocks=(_SEG,)),
           "zbm-seggen": Flow(small={"width": 64, "height": 64, "capacity": 16},
                              fpga_runs=(({}, "full"), ({"capacity": 16}, "reduced")), clocks=(_SEG,)),
           "zbm-unit": Flow(small={"interleave": 2, "width": 64, "height": 64, "capacity": 16},
                            fpga_runs=(({}, "full"), ({"interleave": 2, "width": 64, "height": 64, "capacity": 16},
                                                      "reduced")), clocks=(_SEG, _MERGE))},
    # the chip's Fmax against interleave (paper, sec. 5.3), at a 512-pixel line
    fpga_sweeps=(FpgaSweep("zbm-chip", "interleave", (1, 2, 4, 8, 16), {"width": 512},
                           "ZB/M chip on ECP5-85F, 512-pixel line, out of context", "interleave (chips per unit)",
                           "what the interleave changes in the chip is the initial processor's slot arithmetic and "
                           "the pixel memories, ceil(512 / interleave) double-Z words per line; the loop's 8 pixel "
                           "processors are the same at every interleave."),),
    fpga_note=("ZB/M segment clock 25 MHz (\"ZB/M の入力クロックは 25MHz\", sec. 6.1 cond. 3); the merge clock is "
               "independent (\"マージャはそれとは独立のマージクロックで動作\") and its frequency is not given."),
    testbenches={"zbm-seggen": "rasterhw.sim.zbm.testbench:SeggenBench",
                 "zbm-unit": "rasterhw.sim.zbm.testbench:UnitBench",
                 "zbm-merger": "rasterhw.sim.zbm.testbench:MergerBench",
                 "zbm-chip": "rasterhw.sim.zbm.testbench:ChipBench",
                 "zbm-loop": "rasterhw.sim.zbm.testbench:LoopBench",
                 "zbm-pixel": "rasterhw.sim.zbm.testbench:PixelBench"},
    status="segment generator, ZB/M chip (8 pixel processors on a segment loop, double Z, merger on its own "
           "clock), unit, chained units (HDL, bit- and cycle-exact)",
)
