// Timing-free bench for one EXPERTS PXP (`experts_pxp`), for plain Verilator runs (cocotb_tests/plain_main.cpp
// toggles `clk`). Memories are sized for a 512 x 512 frame at up to 16 x 64 PXP lines (one build
// serves every scene). Stimulus (+seg=, +nseg= words of {next_hi[10:0], next_lo[9:0], payload[SEGW-1:0]}
// (SEGW 194: experts-pxp; 204: experts-pxp-span, the DMM/P words)
// is played back to back; when an end-of-line token (payload bit 0) is taken, the range of the
// next line (next_lo, next_hi) is put on lo/hi, which the PXP samples as the line ends. The first
// line's range comes from +lo0= / +hi0=. Every pixel word is stored in order (dumped to +out=),
// every line's finish-time counter too (+cyc=). `done` rises on the edge after the +nout=-th pixel.
// Optional random timing (+seed=S): +idle=K (1..255) -- a word not yet offered is offered only when
// a seeded 8-bit xorshift number is >= K, and an offered word is held until taken (the stream
// rules); +stall=K -- the output's ready is low when another such number is below K. Both 0 (the
// default): input back to back and output always ready, the cycle-exact run.
module tb_experts_pxp #(
  parameter NSEG = 1 << 19,
  parameter NOUT = 1 << 18,
  parameter NLINE = 1 << 14,
  parameter SEGW = 194
) (
  input clk,
  output reg done,
  output reg [63:0] cycles
);
  reg [SEGW+20:0] stim [0:NSEG-1];
  reg [15:0] frame [0:NOUT-1];
  reg [15:0] lcyc [0:NLINE-1];
  reg [8*512-1:0] fseg, fout, fcyc;
  reg [31:0] lo0, hi0;
  reg [9:0] lo;
  reg [10:0] hi;
  reg [31:0] p, q, nl, nseg, nout;
  integer IDLE, STALL, SEED;
  reg offer;
  reg [31:0] lfi, lfo;
  initial begin
    done = 1'b0;
    cycles = 64'd0;
    p = 0;
    q = 0;
    nl = 0;
    if (!$value$plusargs("seg=%s", fseg)) $fatal(1, "tb_experts_pxp: +seg= missing");
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_experts_pxp: +out= missing");
    if (!$value$plusargs("cyc=%s", fcyc)) $fatal(1, "tb_experts_pxp: +cyc= missing");
    if (!$value$plusargs("nseg=%d", nseg)) $fatal(1, "tb_experts_pxp: +nseg= missing");
    if (!$value$plusargs("nout=%d", nout)) $fatal(1, "tb_experts_pxp: +nout= missing");
    if (!$value$plusargs("lo0=%d", lo0)) lo0 = 0;
    if (!$value$plusargs("hi0=%d", hi0)) hi0 = 1;
    if (!$value$plusargs("idle=%d", IDLE)) IDLE = 0;
    if (!$value$plusargs("stall=%d", STALL)) STALL = 0;
    if (!$value$plusargs("seed=%d", SEED)) SEED = 1;
    offer = 1'b1;
    lfi = 32'h9E3779B9 ^ (SEED * 32'd7919 + 32'd1);
    lfo = 32'h7F4A7C15 ^ (SEED * 32'd104729 + 32'd3);
    lo = lo0[9:0];
    hi = hi0[10:0];
    $readmemh(fseg, stim);
  end
  final begin
    $writememh(fout, frame);
    $writememh(fcyc, lcyc);
  end

  wire [SEGW+20:0] w = stim[p];
  `include "xorshift.vh"   // xorshift32, the one copy (cocotb_tests/xorshift.vh)

  wire iv = (p < nseg) && offer;
  wire ordy = (lfo[7:0] >= STALL);
  wire ir, ov;
  wire [15:0] opl;
  wire [15:0] line_cycles, lines;
  experts_pxp dut (
    .clk(clk), .rst(1'b0),
    .i__valid(iv), .i__ready(ir), .i__payload(w[SEGW-1:0]),
    .o__valid(ov), .o__ready(ordy), .o__payload(opl),
    .lo(lo), .hi(hi), .line_cycles(line_cycles), .lines(lines)
  );
  reg [15:0] seen = 16'd0;
  always @(posedge clk) begin
    cycles <= cycles + 64'd1;
    lfi <= xorshift32(lfi);
    lfo <= xorshift32(lfo);
    if (!offer || ir) offer <= (lfi[7:0] >= IDLE);
    if (iv && ir) begin
      p <= p + 1;
      if (w[0]) begin
        lo <= w[SEGW+9:SEGW];
        hi <= w[SEGW+20:SEGW+10];
      end
    end
    if (ov && ordy) begin
      frame[q] <= opl;
      q <= q + 1;
      if (q + 1 == nout) done <= 1'b1;
    end
    if (lines != seen) begin
      seen <= lines;
      lcyc[nl] <= line_cycles;
      nl <= nl + 1;
    end
  end
endmodule
