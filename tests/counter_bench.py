"""A tiny Verilog bench for the trace tests (tests/test_waves.py, tests/test_waves_window.py): a
cycle counter that raises ``done`` after ``last + 1`` clocks, the port set the C++ main needs."""

from __future__ import annotations


def counter_verilog(name: str, last: int) -> str:
    return f"""module {name} (input clk, output reg done, output reg [7:0] cycles);
  initial begin done = 0; cycles = 0; end
  always @(posedge clk) begin
    cycles <= cycles + 1;
    if (cycles == 8'd{last}) done <= 1;
  end
endmodule
"""
