"""What both trace tests use (tests/test_waves.py, tests/test_waves_window.py): the command line
run in this process, and a tiny Verilog bench -- a cycle counter that raises ``done`` after
``last + 1`` clocks, the port set the C++ main needs."""

from __future__ import annotations

from rasterhw.sim.cli.main import main


def run_cli(argv) -> int:
    """``rasterhw ARGV`` in this process; its exit code."""
    try:
        main(argv)
    except SystemExit as e:
        return e.code or 0
    return 0


def counter_verilog(name: str, last: int) -> str:
    return f"""module {name} (input clk, output reg done, output reg [7:0] cycles);
  initial begin done = 0; cycles = 0; end
  always @(posedge clk) begin
    cycles <= cycles + 1;
    if (cycles == 8'd{last}) done <= 1;
  end
endmodule
"""
