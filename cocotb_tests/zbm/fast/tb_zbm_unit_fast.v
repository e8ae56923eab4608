// Timing-free bench wrapper for a chain of ZB/M units (`zbm_chain_flat`), for plain Verilator
// scene runs (no cocotb, no --timing): the C++ main (../../plain_main.cpp) drives `clk`, which
// clocks both the segment and the merge domain. Same stimulus, sinks and output files as
// ../tb_zbm_unit.v run with equal, in-phase clocks (`+sync_half=5 +merge_half=5
// +merge_phase=0`, what `rasterhw sim zbm` uses): the edge-pair words of every unit
// preloaded and played with their stored idle gaps (+stim=, +index=), every merge slot drained
// with the same seeded random back-pressure (+stall=, +seed=), the frame dumped to +out= and
// the optional per-line log to +lines= by the `final` block, after the timed loop.
// `done` rises (and `cycles` holds unit 0's segment-clock counter) on the clock edge on which
// tb_zbm_unit.v sets `finished`: every slot has its H lines, or a unit's sticky overflow.
// +meta= (a file): one JSON line {"overflow", "frames_ok", "proto_errors"} written at the end.
module tb_zbm_unit_fast #(
  parameter I = 8,
  parameter U = 1,
  parameter W = 64,
  parameter H = 16,
  parameter GW = 8,
  parameter SDEPTH = 1024
) (
  input clk,
  output reg done,
  output reg [31:0] cycles
);
  integer STALL = 0, SEED = 1;
  reg [8*512-1:0] fout, fmeta, flines;
  reg log_lines, has_meta;
  reg overflow, frames_ok;
  reg [31:0] proto_at_end;
  integer fd;

  initial begin
    done = 1'b0;
    cycles = 32'd0;
    overflow = 1'b0;
    frames_ok = 1'b0;
    proto_at_end = 32'd0;
    if (!$value$plusargs("stall=%d", STALL)) STALL = 0;
    if (!$value$plusargs("seed=%d", SEED)) SEED = 1;
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_zbm_unit_fast: +out= missing");
    has_meta = $value$plusargs("meta=%s", fmeta);
    log_lines = $value$plusargs("lines=%s", flines);
  end

  // reset: high for the first 6 rising edges, low from the 7th on (tb_zbm_unit.v releases both
  // resets 0.5 ns after the 6th edge)
  reg [2:0] rcnt = 3'd0;
  always @(posedge clk) if (rcnt != 3'd6) rcnt <= rcnt + 3'd1;
  wire rst = (rcnt != 3'd6);

  // --- the units, their players and the merge-slot sinks (../tb_zbm_unit_core.v), both
  // clock domains on `clk`
  wire [I-1:0] slot_done;
  wire [32*I-1:0] slot_y;
  wire [31:0] cycles0, proto_errors;
  wire any_overflow, all_frames;
  tb_zbm_unit_core #(.I(I), .U(U), .W(W), .H(H), .GW(GW), .SDEPTH(SDEPTH)) core (
    .clk(clk), .rst(rst), .mclk(clk), .mrst(rst), .stall(STALL), .seed(SEED),
    .slot_done(slot_done), .slot_y(slot_y), .cycles0(cycles0), .any_overflow(any_overflow),
    .all_frames(all_frames), .proto_errors(proto_errors));

  // per-line log, as tb_zbm_unit.v: line_t[y] = unit 0's count in the cycle in which the last
  // slot finished merge output line y
  reg [31:0] line_t [0:H-1];
  reg [31:0] ymin, ylog = 32'd0;
  integer e2;
  always @(*) begin
    ymin = H;
    for (e2 = 0; e2 < I; e2 = e2 + 1) if (slot_y[32*e2 +: 32] < ymin) ymin = slot_y[32*e2 +: 32];
  end

  // --- completion ---------------------------------------------------------------------------
  always @(posedge clk) begin
    if (!rst && ylog < ymin) begin
      line_t[ylog] = cycles0;
      ylog = ylog + 32'd1;
    end
    if (!rst && !done && ((&slot_done) || any_overflow)) begin
      cycles <= cycles0;
      overflow <= any_overflow;
      frames_ok <= all_frames;
      proto_at_end <= proto_errors;
      done <= 1'b1;
    end
  end

  final begin
    $writememh(fout, core.frame);
    if (log_lines) $writememh(flines, line_t);
    if (has_meta) begin
      fd = $fopen(fmeta, "w");
      $fdisplay(fd, "{\"overflow\": %0d, \"frames_ok\": %0d, \"proto_errors\": %0d}", overflow, frames_ok,
                proto_at_end);
      $fclose(fd);
    end
  end
endmodule
