"""Registry entry of the SNU graphics system (seed 004): its arch, blocks, sim, report, bench."""

from rasterhw.sim.registry import Arch, Machine, SimBlock

MACHINE = Machine(
    name="snu",
    title="SNU graphics system (Seoul Nat. Univ.)",
    seed="004_259eba1ba2ec22c5.txt",
    archs=(Arch("snu", "SNU fixed-point Gouraud scan converter into the pixel-bus frame buffer model",
                "rasterhw.golden_model.snu.render:render", bytes_per_pixel=120),),  # measured ~88
    blocks={"pixelbus-bank": "rasterhw.hdl.snu.pixelbus_bank:PixelBusBank",
            "pixelbus": "rasterhw.hdl.snu.pixelbus:PixelBus"},
    sims=(SimBlock("pixelbus", "the scene's Gouraud pixel stream through the pixel-bus HDL (5 banks, 2 pipelines)",
                   "rasterhw.sim.snu.pixelbus:simulate_scene", default_scene="snu-100px"),),
    report="rasterhw.sim.snu.report:rows",
    bench="rasterhw.sim.snu.bench:bench",
    soak={"pixelbus": "rasterhw.sim.snu.soak:pixelbus_round"},
    proofs={"pixelbus-bank": "rasterhw.sim.snu.proof:PROOF"},
    status="pixel-bus controller with Z comparator over a 5-bank frame buffer (HDL, bit- and cycle-exact); "
           "i860 timing model, the paper's geometry recipe, Gouraud scan converter, PHIGS traversal (golden); "
           "snu-100k frame end to end (pixel bus on Verilator with clear and swap)",
)
