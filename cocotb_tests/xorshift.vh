// The 32-bit xorshift (Marsaglia 2003: x ^= x << 13; x ^= x >> 17; x ^= x << 5), the one copy every
// Verilog bench includes inside a module (`include "xorshift.vh"; the build puts cocotb_tests/ on
// the include path: sim/engines/runner.py). sim/engines/pattern.py is the same function in Python,
// so a seeded back-pressure or idle pattern is the same clock for clock on every engine.
function [31:0] xorshift32(input [31:0] x);
  reg [31:0] t;
  begin
    t = x ^ (x << 13);
    t = t ^ (t >> 17);
    xorshift32 = t ^ (t << 5);
  end
endfunction
