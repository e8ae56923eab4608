"""Registry entry of EXPERTS (seed 000): its arch, PXP block and sim, report and bench."""

from rasterhw.sim.registry import Arch, Clock, Flow, Machine, Option, SimBlock

_NO_CLOCK = Clock("sync", "EXPERTS: the paper names no clock (times in operation times)", None, "clock")
#: the SLP's and its set-up's datapath in the fpga report's labels (``acc_extra`` 0: the paper's 16-bit
#: words and one 16 x 16 multiplier, ``--datapath paper``; 16, formats.ACC_EXTRA: ours)
_SLP_DATAPATH = {"acc_extra": {0: "datapath paper (acc_extra 0)", 16: "datapath ours (acc_extra 16)"}}
#: the SLP placed at a reduced size at both datapaths (full size: Yosys over 480 s under load, issue 48)
_SLP_REDUCED = {"width": 64, "tris": 64, "lines": 32, "asl": 64}

MACHINE = Machine(
    headline=("fig. 4.1 / text: balance Pn", "table 2.2: work with A.J.", "5: processor op rate for 30 frames/s",
              "4 iv): coherent span PXP (ours: span cull once per segment, depth search where the visible segment "
              "can change): span cull operations, Fr 2000 / Fr 1000",
              "4 v): coherent span PXP (ours: span cull once per segment, depth search where the visible segment "
              "can change): depth search operations, Fr 2000 / Fr 1000",
              "5: SLP with set-up, operation count (model): SLP clock for 30 frames/s, experts-1000",
              "5 / HDL: coherent span PXP (ours, experts-pxp-coherent), HDL cycles",
              "5 / HDL: span PXP (ours, experts-pxp-span), HDL cycles", "5 / HDL: SLP list work",
              "5 / HDL: SLP with set-up (experts-slp-setup, then experts-slp), HDL cycles: SLP clock"),
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
                         Option("shadows", "none, or shadow polygons in the scan line (Crow; our choice, "
                                "the paper gives no method)", "none", ("none", "polygons")),
                         Option("sn", "SLPs (bands of scan lines) for the timing stats", 8, type=int),
                         Option("pn", "PXPs per SLP (ranges of each line) for the timing stats", 8, type=int))),),
    blocks={"experts-pxp": "rasterhw.hdl.experts.pxp:ExpertsPxp",
            "experts-pxp-span": "rasterhw.hdl.experts.pxp_span:ExpertsPxpSpan",
            "experts-pxp-coherent": "rasterhw.hdl.experts.pxp_coherent:ExpertsPxpCoherent",
            "experts-slp": "rasterhw.hdl.experts.slp:ExpertsSlp",
            "experts-slp-setup": "rasterhw.hdl.experts.slp_setup:ExpertsSlpSetup",
            "experts-group": "rasterhw.hdl.experts.group:ExpertsGroup",
            "experts-dmm": "rasterhw.hdl.experts.dmm:ExpertsDmm",
            "experts-pxp-unit": "rasterhw.hdl.experts.unit:ExpertsPxpUnit"},
    sims=(SimBlock("pxp", "every PXP line of the frame through the PXP HDL, against the bit-accurate golden PXP "
                   "(pixels and cycles)", "rasterhw.sim.experts.scene:simulate_scene", default_scene="experts-1000",
                   options=(Option("sn", "SLPs (bands)", 8, type=int),
                            Option("pn", "PXPs per SLP (ranges)", 8, type=int),
                            Option("aj", "anti-jagging in the PXP: none or c", "c", ("none", "a", "b", "c")),
                            Option("ranges", "PXP ranges: static, or set per line by method i / ii from the "
                                   "previous line's finish-time counters", "static", ("static", "i", "ii")),
                            Option("pxp", "PXP: span (span cull at every segment end + depth search per span, "
                                   "experts-pxp-span), coherent (span cull once per segment + depth search where "
                                   "the visible segment can change, experts-pxp-coherent) or zbuffer (a one-line "
                                   "Z-buffer, experts-pxp); all ours, the same pixels. sim experts: default (coherent; span "
                                   "with --path group), coherent or span. sim pxp", "span",
                                   ("span", "coherent", "zbuffer")))),
          SimBlock("experts", "the whole frame: every band through the SLP's set-up HDL (experts-slp-setup) and "
                   "list-work HDL (experts-slp), its ASL order and "
                   "block lists then into every PXP's DMM/P (--pxp: experts-pxp-coherent or experts-pxp-span); "
                   "words, pixels and cycles "
                   "against golden, SLP and PXP clocks for 30 frames/s", "rasterhw.sim.experts.scene:simulate_frame",
                   default_scene="experts-1000",
                   options=(Option("sn", "SLPs (bands)", 8, type=int),
                            Option("pn", "PXPs per SLP (ranges)", 8, type=int),
                            Option("aj", "anti-jagging in the PXP: none or c", "c", ("none", "c")),
                            Option("path", "chained (the SLP HDL, then the PXP HDL on its words, each against its "
                                   "cycle model) or group (one SLP + Pn PXPs clocked together per band, "
                                   "experts-group; pixels against golden, cycles measured)", "chained",
                                   ("chained", "group")),
                            Option("datapath", "ours (today's HDL: 40-bit registers, several multipliers in the "
                                   "PXP) or paper (the paper's 16-bit words, one multiplier a processor: the golden "
                                   "bit model at those widths, the SLP, its set-up and the PXP in HDL at them: z and "
                                   "i in two words); paper also reports the golden bit model's error against float",
                                   "ours", ("ours", "paper")),
                            Option("accuracy", "also the golden bit model's error against the float model (renders "
                                   "the float model; always on with --datapath paper)", False, type=bool),
                            Option("pxp", "the chained frame's PXP: coherent (experts-pxp-coherent: span cull once per "
                                   "segment + depth search where the visible segment can change), span "
                                   "(experts-pxp-span: span cull at every segment end + depth search per span); "
                                   "both ours, the same pixels; default: coherent, span with --path group (its PXPs)",
                                   "default", ("default", "coherent", "span"))),
                   no_image={"path": "group"}),),   # the group's bands: pixels compared, no frame written
    report="rasterhw.sim.experts.report:rows",
    bench="rasterhw.sim.experts.bench:bench",
    soak={"pxp": "rasterhw.sim.experts.soak:pxp_round"},
    flows={"experts-dmm": Flow(small={"depth": 16}, clocks=(_NO_CLOCK,)),
           "experts-pxp": Flow(small={"width": 64}, clocks=(_NO_CLOCK,)),
           # with and without A.J. (c) (at the paper's datapath the blend shares the one multiplier)
           "experts-pxp-span": Flow(small={"width": 64, "depth": 16}, clocks=(_NO_CLOCK,),
                                    fpga_runs=(({"datapath": "paper"}, "full"), ({"datapath": "paper", "aj": "c"}, "full"),
                                               ({}, "full"), ({"aj": "c"}, "full")),
                                    labels={"aj": {"none": "A.J. none", "c": "A.J. (c)"}}),
           # the default PXP at both datapaths (at the paper's: one shared 16 x 16 multiplier, z and i in two words)
           "experts-pxp-coherent": Flow(small={"width": 64, "depth": 16}, clocks=(_NO_CLOCK,),
                                        fpga_runs=(({"datapath": "paper"}, "full"), ({}, "full"))),
           "experts-slp": Flow(small={"width": 64, "tris": 64, "lines": 16, "asl": 32}, clocks=(_NO_CLOCK,),
                               fpga_runs=(({"acc_extra": 0}, "full"), ({}, "full"),
                                          ({**_SLP_REDUCED, "acc_extra": 0}, "reduced"), (_SLP_REDUCED, "reduced")),
                               labels=_SLP_DATAPATH),
           # no reduced set-up: its one size, height, is a clamp constant (the ROM and multiplier do not scale)
           "experts-slp-setup": Flow(small={"height": 64}, clocks=(_NO_CLOCK,),
                                     fpga_runs=(({"acc_extra": 0}, "full"), ({}, "full")), labels=_SLP_DATAPATH),
           "experts-group": Flow(small={"width": 64, "pn": 2, "tris": 64, "lines": 16, "asl": 32, "depth": 32},
                                 clocks=(_NO_CLOCK,)),
           "experts-pxp-unit": Flow(small={"width": 64, "depth": 16}, clocks=(_NO_CLOCK,))},
    fpga_note="EXPERTS names no clock (docs/experts.md: times in operation times).",
    testbenches={"experts-pxp": "rasterhw.sim.experts.testbench:PxpBench",
                 "experts-pxp-span": "rasterhw.sim.experts.testbench:PxpSpanBench",
                 "experts-pxp-coherent": "rasterhw.sim.experts.testbench:PxpCoherentBench",
                 "experts-slp": "rasterhw.sim.experts.testbench:SlpBench",
                 "experts-slp-setup": "rasterhw.sim.experts.testbench:SlpSetupBench",
                 "experts-group": "rasterhw.sim.experts.testbench:GroupBench",
                 "experts-pxp-unit": "rasterhw.sim.experts.testbench:PxpUnitBench",
                 "experts-dmm": "rasterhw.sim.experts.testbench:DmmBench"},
    status="scan-line golden model split as SLP/PXP (float and 16-bit): span PXPs (the paper's span cull, "
           "depth search per span) and the SLP's sorts run and counted, Sn x Pn parallel model with "
           "load balancing at both levels, fig. 4.1 cost model (golden); in HDL, bit- and cycle-exact: the "
           "span PXP (default), the coherent span PXP and the line-Z-buffer PXP (all ours), the SLP (Y-sort, ASL "
           "update, L-sort, X-merge, block lists) and its set-up (multiplier, reciprocal ROM); one SLP + Pn PXPs "
           "clocked together (pixel-exact)",
)
