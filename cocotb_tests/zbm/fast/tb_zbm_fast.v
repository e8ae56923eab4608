// Timing-free bench wrapper for one ZB/M chip (`zbm_chip`), for plain Verilator runs
// (no cocotb, no --timing): the C++ main (../../plain_main.cpp) drives `clk`, which clocks both the
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

  reg [MW-1:0] frame [0:NOUT-1];
  reg [31:0] nseg, nup, REPEAT;
  reg [8*512-1:0] fout;
  integer k0;

  initial begin
    done = 1'b0;
    cycles = 32'd0;
    lines = 32'd0;
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_zbm_fast: +out= missing");
    if (!$value$plusargs("nseg=%d", nseg)) $fatal(1, "tb_zbm_fast: +nseg= missing");
    if (!$value$plusargs("nup=%d", nup)) $fatal(1, "tb_zbm_fast: +nup= missing");
    if (!$value$plusargs("repeat=%d", REPEAT)) REPEAT = 32'd1;
    for (k0 = 0; k0 < NOUT; k0 = k0 + 1) frame[k0] = {MW{1'b1}};
  end

  final $writememh(fout, frame);

  // reset: high for the first 6 rising edges, low from the 7th on (as tb_zbm_chip.v, which
  // releases it 0.5 ns after the 6th edge)
  reg [2:0] rcnt = 3'd0;
  always @(posedge clk) if (rcnt != 3'd6) rcnt <= rcnt + 3'd1;
  wire rst = (rcnt != 3'd6);

  // --- stimulus players (../../harness.v) ------------------------------------------------
  wire seg_v, seg_r, up_v, up_r, seg_done, up_done;
  wire [SEGW-1:0] seg_p;
  wire [MW-1:0] up_p;
  rasterhw_stream_player #(.PW(SEGW), .GW(GW), .DEPTH(SDEPTH), .FILE_ARG("seg=%s")) seg_player (
    .clk(clk), .rst(rst), .base(32'd0), .count(nseg), .repeats(REPEAT),
    .valid(seg_v), .ready(seg_r), .payload(seg_p), .done(seg_done));
  rasterhw_stream_player #(.PW(MW), .GW(GW), .DEPTH(MDEPTH), .FILE_ARG("up=%s")) up_player (
    .clk(clk), .rst(rst), .base(32'd0), .count(nup), .repeats(REPEAT),
    .valid(up_v), .ready(up_r), .payload(up_p), .done(up_done));

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
