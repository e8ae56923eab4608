"""Registry entry of the matrix-pipeline generator on sparse rasters (seed 002)."""

from __future__ import annotations

from rasterhw.sim.registry import Arch, Clock, Flow, Machine, Option, SimBlock

_MATRIX = Option(name="matrix", help="matrix of video processors PxQ (powers of two; the raster must be "
                                     "p*2^n x q*2^n)", default="4x4")

_COUPLED = Option(name="coupled", type=bool, default=True,
                  help="the whole matrix in one simulation (broadcast, input FIFOs, back-pressure); "
                       "--no-coupled: every processor alone on the full stream, one simulation each")
_FIFO_DEPTH = Option(name="fifo_depth", type=int, default=64,
                     help="coupled matrix: every processor's input FIFO depth, 1..64 (a run-time limit inside "
                          "one 64-entry build)")
_VP_FIFO_DEPTH = Option(name="vp_fifo_depth", type=int, default=None,
                        help="coupled matrix: depth of the FIFOs between a processor's levels, 2..64 (a build "
                             "parameter; the paper gives no size: every depth is ours); unset: 8, a queue of windows "
                             "inside the processor, the depth that reproduces formulas (9) and (10) (as --no-coupled "
                             "builds it); 2: the shallowest")

_VP = Option(name="vp", default="pipeline", choices=("pipeline", "stack"),
             help="coupled matrix: the video processors' raster processor: the pipeline (one stage per level, "
                  "the default) or the stack-based processor (in the paper \"процессор со стеком\"; ours: one "
                  "coverage-test unit and a stack)")

_COLOUR = Option(name="colour", type=bool, default=False,
                 help="coupled matrix: surface parameters: the vertex colours broadcast as three linear functions, "
                      "written with the Z test, compared with the golden colour (colour_mismatches)")
_KP = Option(name="kp", type=int, default=0,
             help="coupled matrix: formula (5)'s cost in cycles of kp parameter additions per surviving window on "
                  "k_e = 3 edge adders, 0..15 (0: unpriced, as depth alone; 4: depth + RGB)")

_HIERARCHICAL = Option(name="hierarchical", type=bool, default=None,
                      help="coupled matrix on Verilator: the cell verilated and compiled once (Verilator's "
                           "hierarchical verilation): the same model, a much shorter build, a slower clock loop; "
                           "unset: hierarchical from 4x4 up, flat below; --no-hierarchical: always flat")

_NO_CLOCK = Clock("sync", "sparse video processor: the paper names no clock", None, "clock")

MACHINE = Machine(
    name="sparse",
    title="Matrix-pipeline generator on sparse rasters (recursive pixel search)",
    seed="002_a1ff7020b0ad58f6.txt",
    archs=(
        Arch(name="sparse",
             help="p x q matrix of video processors, recursive pixel search on sparse rasters "
                  "(image equals the reference)",
             render="rasterhw.golden_model.sparse.render:render",
             options=(_MATRIX,), bytes_per_pixel=700),  # measured ~540 (peak RSS, 1024 x 1024)
    ),
    blocks={"sparse-vp": "rasterhw.hdl.sparse.vp:make_vp", "sparse-matrix": "rasterhw.hdl.sparse.matrix:make_matrix",
            "sparse-stack-vp": "rasterhw.hdl.sparse.stack_vp:make_stack_vp"},
    sims=(SimBlock(name="sparse", help="every video processor of the matrix in HDL, interleaved local memories "
                                       "against the bit-accurate golden model",
                   simulate="rasterhw.sim.sparse.scene:simulate", default_scene="c300",
                   options=(_MATRIX, _COUPLED, _FIFO_DEPTH, _VP_FIFO_DEPTH, _VP, _COLOUR, _KP, _HIERARCHICAL),
                   aliases=("frame_cycles",),   # = cycles (the report reads it under this name)
                   no_image={"coupled": False},   # one processor's run alone: no frame to write
                   bytes_per_pixel=700),),
    report="rasterhw.sim.sparse.report:rows",
    bench="rasterhw.sim.sparse.bench:bench",
    testbenches={"sparse-vp": "rasterhw.sim.sparse.testbench:VPBench",
                 "sparse-matrix": "rasterhw.sim.sparse.testbench:MatrixBench",
                 "sparse-stack-vp": "rasterhw.sim.sparse.testbench:StackVPBench"},
    soak={"sparse": "rasterhw.sim.sparse.soak:sparse_round"},
    flows={"sparse-vp": Flow(small={"n": 4, "p": 2, "q": 2}, clocks=(_NO_CLOCK,)),
           "sparse-matrix": Flow(small={"n": 3, "in_depth": 4}, clocks=(_NO_CLOCK,)),
           "sparse-stack-vp": Flow(small={"n": 4, "p": 2, "q": 2}, clocks=(_NO_CLOCK,))},
    fpga_note="The sparse video processor's paper names no clock (docs/sparse.md).",
    status="golden model (image = reference), formulas (1)-(12), Monte-Carlo window counts, figs. 3-6; "
           "video processor in Amaranth, bit-exact in pysim and Verilator; the whole matrix (broadcast, input FIFOs, "
           "back-pressure, interleaved read-out) in one simulation, bit- and cycle-exact at 1024² 4x4; golden cycle models of the coupled "
           "matrix (FIFO sizing), of the HDL video processor (cycle-exact) and of a stack-based processor; the stack-based "
           "processor in Amaranth, bit- and cycle-exact against its golden model",
)
