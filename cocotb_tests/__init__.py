"""cocotb benches on the generated Verilog (run through rasterhw.sim.engines.runner)."""
