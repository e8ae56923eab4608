"""Registry entry of the SNU graphics system (seed 004): its arch, blocks, sim, report, bench."""

from rasterhw.sim.registry import Arch, Clock, Flow, Machine, SimBlock

#: the pixel bus's clock: one 80 ns slot, the bank's 400 ns memory cycle being 5 slots (sec. 3)
_SLOT = Clock("sync", "SNU pixel-bus slot 80 ns (bank memory cycle 400 ns = 5 slots)", 12.5e6, "pixel-bus clock")


def ram_bits(params: dict[str, int]) -> int:
    """Bits of one ``rasterhw_pixelbus_ram`` instance (the frame memory chips) from its parameters."""
    return params["WIDTH"] * params["DEPTH"]


MACHINE = Machine(
    headline=("table 1: total operations per triangle", "text 3.2: pixel-bus rate",
              "abstract: snu-100k polygons/s", "abstract: geometry-bound polygons/s",
              "text 4.5: polygons/s per 3-processor pipeline"),
    name="snu",
    title="SNU graphics system (Seoul Nat. Univ.)",
    seed="004_259eba1ba2ec22c5.txt",
    archs=(Arch("snu", "SNU fixed-point Gouraud scan converter into the pixel-bus frame buffer model",
                "rasterhw.golden_model.snu.render:render", bytes_per_pixel=120),),  # measured ~88
    blocks={"pixelbus-bank": "rasterhw.hdl.snu.pixelbus_bank:PixelBusBank",
            "pixelbus": "rasterhw.hdl.snu.pixelbus:PixelBus"},
    sims=(SimBlock("pixelbus", "the scene's Gouraud pixel stream through the pixel-bus HDL (5 banks, 2 pipelines)",
                   "rasterhw.sim.snu.scene:simulate", default_scene="snu-100px"),),
    report="rasterhw.sim.snu.report:rows",
    bench="rasterhw.sim.snu.bench:bench",
    soak={"pixelbus": "rasterhw.sim.snu.soak:pixelbus_round"},
    proofs={"pixelbus-bank": "rasterhw.sim.snu.proof:PROOF"},
    testbenches={"pixelbus-bank": "rasterhw.sim.snu.testbench:BankBench",
                 "pixelbus": "rasterhw.sim.snu.testbench:BusBench"},
    flows={"pixelbus-bank": Flow(synth={"ram": "verilog", "depth": 1280 * 1024 // 5},  # one of 5 banks of the frame
                                 small={"depth": 64}, fpga={"ram": "memory", "depth": 4096},
                                 fpga_runs=(({}, "full"), ({"ram": "memory", "depth": 4096}, "reduced")),
                                 clocks=(_SLOT,), demand_from_synth=True),
           "pixelbus": Flow(synth={"ram": "verilog"}, small={"width": 40, "height": 16},
                            fpga={"ram": "memory", "width": 160, "height": 128},
                            fpga_runs=(({}, "full"), ({"ram": "memory", "width": 160, "height": 128}, "reduced")),
                            clocks=(_SLOT,), demand_from_synth=True)},
    # the frame memory outside the controller: a black box in synthesis (sim/flow/synth.py)
    ram_modules={"rasterhw_pixelbus_ram": "rasterhw.sim.snu.machine:ram_bits"},
    fpga_note="SNU: 80 ns pixel-bus slot, the bank's 400 ns memory cycle being 5 slots.",
    status="pixel-bus controller with Z comparator over a 5-bank frame buffer (HDL, bit- and cycle-exact); "
           "i860 timing model, the paper's geometry recipe, Gouraud scan converter, PHIGS traversal (golden); "
           "snu-100k frame end to end (pixel bus on Verilator with clear and swap)",
)
