// Timing-free bench wrapper for one ZB/M chip (`zbm_chip`), for plain Verilator runs
// (no cocotb, no --timing): the C++ main (main.cpp) drives `clk`, which clocks both the
// segment and the merge domain. Same stimulus/output scheme as ../zbm/tb_zbm_chip.v with
// equal, in-phase clocks, no back-pressure and no stream checkers: segment words
// (+seg=, {gap[GW-1:0], word[111:0]}) and upstream merge pixels (+up=, {gap, pixel[127:0]})
// preloaded with $readmemh and played with their idle gaps, +repeat= times; the merged
// output of the last repetition is dumped to +out= by the `final` block (after the timed loop).
// `done` rises (and `cycles` holds the chip's segment-clock counter) on the clock edge after
// the last output word was taken -- the same edge and value as tb_zbm_chip.v's `finished`.
module tb_zbm_fast #(
  parameter I = 8,
  parameter CHIP = 0,
  parameter W = 64,
  parameter L = 16,
  parameter GW = 8,
  parameter SDEPTH = 1024,
  parameter MDEPTH = 1024
) (
  input clk,
  output reg done,
  output reg [31:0] cycles,
  output reg [31:0] lines
);
  localparam SEGW = 112;
  localparam MW = 128;
  localparam NPX = (W - CHIP + I - 1) / I;
  localparam NOUT = NPX * L;

  reg [GW+SEGW-1:0] seg [0:SDEPTH-1];
  reg [GW+MW-1:0] up [0:MDEPTH-1];
  reg [MW-1:0] frame [0:NOUT-1];
  reg [31:0] nseg, nup, REPEAT;
  reg [8*512-1:0] fseg, fup, fout;
  integer k0;

  initial begin
    done = 1'b0;
    cycles = 32'd0;
    lines = 32'd0;
    if (!$value$plusargs("seg=%s", fseg)) $fatal(1, "tb_zbm_fast: +seg= missing");
    if (!$value$plusargs("up=%s", fup)) $fatal(1, "tb_zbm_fast: +up= missing");
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_zbm_fast: +out= missing");
    if (!$value$plusargs("nseg=%d", nseg)) $fatal(1, "tb_zbm_fast: +nseg= missing");
    if (!$value$plusargs("nup=%d", nup)) $fatal(1, "tb_zbm_fast: +nup= missing");
    if (!$value$plusargs("repeat=%d", REPEAT)) REPEAT = 32'd1;
    $readmemh(fseg, seg);
    $readmemh(fup, up);
    for (k0 = 0; k0 < NOUT; k0 = k0 + 1) frame[k0] = {MW{1'b1}};
  end

  final $writememh(fout, frame);

  // reset: high for the first 6 rising edges, low from the 7th on (as tb_zbm_chip.v, which
  // releases it 0.5 ns after the 6th edge)
  reg [2:0] rcnt = 3'd0;
  always @(posedge clk) if (rcnt != 3'd6) rcnt <= rcnt + 3'd1;
  wire rst = (rcnt != 3'd6);

  // --- segment player ------------------------------------------------------------------
  reg [31:0] sp, srep;
  reg [GW-1:0] swt;
  wire [GW+SEGW-1:0] scur = seg[sp[$clog2(SDEPTH)-1:0]];
  wire [31:0] sp1 = (sp + 1 == nseg) ? 32'd0 : sp + 32'd1;
  wire [GW+SEGW-1:0] snxt = seg[sp1[$clog2(SDEPTH)-1:0]];
  wire seg_v = !rst && (srep < REPEAT) && (sp < nseg) && (swt == {GW{1'b0}});
  wire seg_r;
  wire [SEGW-1:0] seg_p = scur[SEGW-1:0];
  always @(posedge clk) begin
    if (rst) begin
      sp <= 32'd0;
      srep <= 32'd0;
      swt <= seg[0][GW+SEGW-1:SEGW];
    end else if (seg_v && seg_r) begin
      sp <= sp1;
      if (sp + 1 == nseg) srep <= srep + 32'd1;
      swt <= snxt[GW+SEGW-1:SEGW];
    end else if (swt != {GW{1'b0}}) begin
      swt <= swt - 1'b1;
    end
  end

  // --- upstream merge-port player ----------------------------------------------------------
  reg [31:0] upp, urep;
  reg [GW-1:0] uwt;
  wire [GW+MW-1:0] ucur = up[upp[$clog2(MDEPTH)-1:0]];
  wire [31:0] upp1 = (upp + 1 == nup) ? 32'd0 : upp + 32'd1;
  wire [GW+MW-1:0] unxt = up[upp1[$clog2(MDEPTH)-1:0]];
  wire up_v = !rst && (urep < REPEAT) && (upp < nup) && (uwt == {GW{1'b0}});
  wire up_r;
  wire [MW-1:0] up_p = ucur[MW-1:0];
  always @(posedge clk) begin
    if (rst) begin
      upp <= 32'd0;
      urep <= 32'd0;
      uwt <= up[0][GW+MW-1:MW];
    end else if (up_v && up_r) begin
      upp <= upp1;
      if (upp + 1 == nup) urep <= urep + 32'd1;
      uwt <= unxt[GW+MW-1:MW];
    end else if (uwt != {GW{1'b0}}) begin
      uwt <= uwt - 1'b1;
    end
  end

  // --- device under test ---------------------------------------------------------------------
  wire o_v;
  wire [MW-1:0] o_p;
  wire [31:0] dut_cycles, dut_busy;
  wire [15:0] dut_lines;
  wire o_r = !rst;

  zbm_chip dut (
    .clk(clk), .rst(rst), .merge_clk(clk), .merge_rst(rst),
    .i_seg__valid(seg_v), .i_seg__ready(seg_r), .i_seg__payload(seg_p),
    .i_merge__valid(up_v), .i_merge__ready(up_r), .i_merge__payload(up_p),
    .o_merge__valid(o_v), .o_merge__ready(o_r), .o_merge__payload(o_p),
    .cycles(dut_cycles), .busy_cycles(dut_busy), .lines(dut_lines)
  );

  // --- sink: always ready, last repetition kept ----------------------------------------------
  reg [31:0] got, oaddr;
  always @(posedge clk) begin
    if (rst) begin
      got <= 32'd0;
      oaddr <= 32'd0;
    end else if (o_v && o_r && got < NOUT * REPEAT) begin
      frame[oaddr] <= o_p;
      got <= got + 32'd1;
      oaddr <= (oaddr + 1 == NOUT) ? 32'd0 : oaddr + 32'd1;
    end
  end

  always @(posedge clk) begin
    if (!rst && !done && got == NOUT * REPEAT) begin
      cycles <= dut_cycles;
      lines <= {16'd0, dut_lines};
      done <= 1'b1;
    end
  end
endmodule
