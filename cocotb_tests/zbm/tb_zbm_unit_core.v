// What the two ZB/M unit benches share: tb_zbm_unit.v (cocotb, Verilog-side segment and merge
// clocks) and fast/tb_zbm_unit_fast.v (plain Verilator, one clock from the C++ main) each put
// their own clocks, resets, completion and dumps around this one.
//
// Inside: the chain of units (`zbm_chain_flat`), one stimulus player per unit input stream
// (+stim=, ../harness.v) with the index file (+index=: for unit k two hex lines, first
// stimulus word and number of words), one sink per merge slot with seeded random
// back-pressure (ready low when an 8-bit xorshift number is below `stall`; 0 = never) that
// writes the frame memory `frame` in screen order (pixel (x, y) at y*W + x, all ones until
// written), and stream checkers on every port.
// Outputs: per slot `slot_done` (all H lines taken) and `slot_y` (lines taken); unit 0's
// segment-clock counter `cycles0`; `any_overflow` (a unit's sticky overflow); `all_frames`
// (every unit counted one frame) and `proto_errors` (stream-rule violations, all ports).
module tb_zbm_unit_core #(
  parameter I = 8,             // interleave (merge slots)
  parameter U = 1,             // units
  parameter W = 64,
  parameter H = 16,
  parameter GW = 8,            // gap bits
  parameter SDEPTH = 1024      // stimulus memory depth (> all words + 1)
) (
  input clk,
  input rst,
  input mclk,
  input mrst,
  input [31:0] stall,
  input [31:0] seed,
  output [I-1:0] slot_done,
  output [32*I-1:0] slot_y,
  output [31:0] cycles0,
  output any_overflow,
  output reg all_frames,
  output reg [31:0] proto_errors
);
  localparam EW = 168;
  localparam MW = 128;
  localparam NPIX = W * H;

  reg [31:0] idx [0:2*U-1];
  reg [MW-1:0] frame [0:NPIX-1];
  reg [8*512-1:0] findex;
  integer k0;
  initial begin
    if (!$value$plusargs("index=%s", findex)) $fatal(1, "tb_zbm_unit: +index= missing");
    $readmemh(findex, idx);
    for (k0 = 0; k0 < NPIX; k0 = k0 + 1) frame[k0] = {MW{1'b1}};
  end

  // --- device under test ----------------------------------------------------------------
  wire [U-1:0] i_valid, i_ready;
  wire [EW*U-1:0] i_payload;
  wire [I-1:0] o_valid, o_ready;
  wire [MW*I-1:0] o_payload;
  wire [32*U-1:0] dut_cycles;
  wire [16*U-1:0] dut_frames;
  wire [U-1:0] dut_overflow;
  assign cycles0 = dut_cycles[31:0];
  assign any_overflow = |dut_overflow;

  zbm_chain_flat dut (
    .clk(clk), .rst(rst), .merge_clk(mclk), .merge_rst(mrst),
    .i_valid(i_valid), .i_ready(i_ready), .i_payload(i_payload),
    .o_valid(o_valid), .o_ready(o_ready), .o_payload(o_payload),
    .cycles(dut_cycles), .frames(dut_frames), .overflow(dut_overflow)
  );

  // --- one player per unit input stream ---------------------------------------------------
  wire [32*U-1:0] in_err;
  genvar k;
  generate
    for (k = 0; k < U; k = k + 1) begin : player
      wire [31:0] base = idx[2*k];
      wire [31:0] count = idx[2*k+1];
      wire v, done;
      wire r = i_ready[k];
      wire [EW-1:0] p;
      assign i_valid[k] = v;
      assign i_payload[k*EW +: EW] = p;
      // every player loads the whole stimulus file and plays its own unit's words
      rasterhw_stream_player #(.PW(EW), .GW(GW), .DEPTH(SDEPTH), .FILE_ARG("stim=%s")) u (
        .clk(clk), .rst(rst), .base(base), .count(count), .repeats(32'd1),
        .valid(v), .ready(r), .payload(p), .done(done));
      wire [31:0] transfers;
      rasterhw_stream_check #(.PW(EW)) chk (.clk(clk), .rst(rst), .valid(v), .ready(r), .payload(p),
                                       .errors(in_err[32*k +: 32]), .transfers(transfers));
    end
  endgenerate

  // --- one sink per merge slot: random back-pressure, frame address from arrival order ---
  `include "xorshift.vh"   // xorshift32, the one copy (cocotb_tests/xorshift.vh)

  wire [32*I-1:0] faddr;
  wire [32*I-1:0] out_err;
  genvar c;
  generate
    for (c = 0; c < I; c = c + 1) begin : slot
      localparam integer NPX = (W - c + I - 1) / I;
      reg [31:0] lf;
      reg [31:0] q, y;
      wire v = o_valid[c];
      wire r = !mrst && (lf[7:0] >= stall);
      wire [MW-1:0] p = o_payload[c*MW +: MW];
      assign o_ready[c] = r;
      assign slot_done[c] = (y == H);
      assign slot_y[32*c +: 32] = y;
      assign faddr[32*c +: 32] = y * W + q * I + c;
      always @(posedge mclk) begin
        if (mrst) begin
          lf <= 32'h9E3779B9 ^ (seed * 32'd7919 + c * 32'd104729 + 32'd1);
          q <= 32'd0;
          y <= 32'd0;
        end else begin
          lf <= xorshift32(lf);
          if (v && r && y < H) begin
            if (q == NPX - 1) begin
              q <= 32'd0;
              y <= y + 32'd1;
            end else begin
              q <= q + 32'd1;
            end
          end
        end
      end
      wire [31:0] transfers;
      rasterhw_stream_check #(.PW(MW)) chk (.clk(mclk), .rst(mrst), .valid(v), .ready(r), .payload(p),
                                       .errors(out_err[32*c +: 32]), .transfers(transfers));
    end
  endgenerate

  integer s;
  always @(posedge mclk) begin
    if (!mrst) begin
      for (s = 0; s < I; s = s + 1)
        if (o_valid[s] && o_ready[s] && !slot_done[s]) frame[faddr[32*s +: 32]] <= o_payload[s*MW +: MW];
    end
  end

  integer e;
  always @(*) begin
    proto_errors = 32'd0;
    for (e = 0; e < U; e = e + 1) proto_errors = proto_errors + in_err[32*e +: 32];
    for (e = 0; e < I; e = e + 1) proto_errors = proto_errors + out_err[32*e +: 32];
    all_frames = 1'b1;
    for (e = 0; e < U; e = e + 1) all_frames = all_frames && (dut_frames[16*e +: 16] == 16'd1);
  end
endmodule
