"""The ZB/M cocotb cross-check of the generic engines (unit and chip benches on the generated
Verilog, Verilog-side clocks, the Python stream checkers): a test of the engine, kept out of the
package (``tests/zbm/test_zbm_cocotb.py``, ``test_zbm_unit_engine.py``, ``test_zbm_chip_engine.py``,
``tests/test_engine_clocks.py`` use it)."""
