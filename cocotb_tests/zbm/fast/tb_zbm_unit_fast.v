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
  localparam EW = 168;
  localparam MW = 128;
  localparam NPIX = W * H;

  integer STALL = 0, SEED = 1;
  reg [31:0] idx [0:2*U-1];
  reg [MW-1:0] frame [0:NPIX-1];
  reg [8*512-1:0] findex, fout, fmeta, flines;
  reg log_lines, has_meta;
  reg overflow, frames_ok;
  reg [31:0] proto_at_end;
  integer k0, fd;

  initial begin
    done = 1'b0;
    cycles = 32'd0;
    overflow = 1'b0;
    frames_ok = 1'b0;
    proto_at_end = 32'd0;
    if (!$value$plusargs("stall=%d", STALL)) STALL = 0;
    if (!$value$plusargs("seed=%d", SEED)) SEED = 1;
    if (!$value$plusargs("index=%s", findex)) $fatal(1, "tb_zbm_unit_fast: +index= missing");
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_zbm_unit_fast: +out= missing");
    has_meta = $value$plusargs("meta=%s", fmeta);
    log_lines = $value$plusargs("lines=%s", flines);
    $readmemh(findex, idx);
    for (k0 = 0; k0 < NPIX; k0 = k0 + 1) frame[k0] = {MW{1'b1}};
  end

  // reset: high for the first 6 rising edges, low from the 7th on (tb_zbm_unit.v releases both
  // resets 0.5 ns after the 6th edge)
  reg [2:0] rcnt = 3'd0;
  always @(posedge clk) if (rcnt != 3'd6) rcnt <= rcnt + 3'd1;
  wire rst = (rcnt != 3'd6);

  // --- device under test ----------------------------------------------------------------
  wire [U-1:0] i_valid, i_ready;
  wire [EW*U-1:0] i_payload;
  wire [I-1:0] o_valid, o_ready;
  wire [MW*I-1:0] o_payload;
  wire [32*U-1:0] dut_cycles;
  wire [16*U-1:0] dut_frames;
  wire [U-1:0] dut_overflow;

  zbm_chain_flat dut (
    .clk(clk), .rst(rst), .merge_clk(clk), .merge_rst(rst),
    .i_valid(i_valid), .i_ready(i_ready), .i_payload(i_payload),
    .o_valid(o_valid), .o_ready(o_ready), .o_payload(o_payload),
    .cycles(dut_cycles), .frames(dut_frames), .overflow(dut_overflow)
  );

  // --- one player per unit input stream (../../harness.v) ---------------------------------
  wire [32*U-1:0] in_err;
  genvar k;
  generate
    for (k = 0; k < U; k = k + 1) begin : player
      wire [31:0] base = idx[2*k];
      wire [31:0] count = idx[2*k+1];
      wire v, pdone;
      wire r = i_ready[k];
      wire [EW-1:0] p;
      assign i_valid[k] = v;
      assign i_payload[k*EW +: EW] = p;
      rasterhw_stream_player #(.PW(EW), .GW(GW), .DEPTH(SDEPTH), .FILE_ARG("stim=%s")) u (
        .clk(clk), .rst(rst), .base(base), .count(count), .repeats(32'd1),
        .valid(v), .ready(r), .payload(p), .done(pdone));
      wire [31:0] transfers;
      rasterhw_stream_check #(.PW(EW)) chk (.clk(clk), .rst(rst), .valid(v), .ready(r), .payload(p),
                                       .errors(in_err[32*k +: 32]), .transfers(transfers));
    end
  endgenerate

  // --- one sink per merge slot: the same back-pressure and frame addressing as tb_zbm_unit.v
  function [31:0] xorshift(input [31:0] x);
    reg [31:0] a;
    begin
      a = x ^ (x << 13);
      a = a ^ (a >> 17);
      xorshift = a ^ (a << 5);
    end
  endfunction

  wire [I-1:0] slot_done;
  wire [32*I-1:0] slot_y;
  wire [32*I-1:0] faddr;
  wire [32*I-1:0] out_err;
  genvar c;
  generate
    for (c = 0; c < I; c = c + 1) begin : slot
      localparam integer NPX = (W - c + I - 1) / I;
      reg [31:0] lf;
      reg [31:0] q, y;
      wire v = o_valid[c];
      wire r = !rst && (lf[7:0] >= STALL);
      wire [MW-1:0] p = o_payload[c*MW +: MW];
      assign o_ready[c] = r;
      assign slot_done[c] = (y == H);
      assign slot_y[32*c +: 32] = y;
      assign faddr[32*c +: 32] = y * W + q * I + c;
      always @(posedge clk) begin
        if (rst) begin
          lf <= 32'h9E3779B9 ^ (SEED * 32'd7919 + c * 32'd104729 + 32'd1);
          q <= 32'd0;
          y <= 32'd0;
        end else begin
          lf <= xorshift(lf);
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
      rasterhw_stream_check #(.PW(MW)) chk (.clk(clk), .rst(rst), .valid(v), .ready(r), .payload(p),
                                       .errors(out_err[32*c +: 32]), .transfers(transfers));
    end
  endgenerate

  integer s;
  always @(posedge clk) begin
    if (!rst) begin
      for (s = 0; s < I; s = s + 1)
        if (o_valid[s] && o_ready[s] && !slot_done[s]) frame[faddr[32*s +: 32]] <= o_payload[s*MW +: MW];
    end
  end

  // --- completion ---------------------------------------------------------------------------
  integer e;
  reg [31:0] proto_errors;
  reg all_frames;
  always @(*) begin
    proto_errors = 32'd0;
    for (e = 0; e < U; e = e + 1) proto_errors = proto_errors + in_err[32*e +: 32];
    for (e = 0; e < I; e = e + 1) proto_errors = proto_errors + out_err[32*e +: 32];
    all_frames = 1'b1;
    for (e = 0; e < U; e = e + 1) all_frames = all_frames && (dut_frames[16*e +: 16] == 16'd1);
  end

  // per-line log, as tb_zbm_unit.v: line_t[y] = unit 0's count in the cycle in which the last
  // slot finished merge output line y
  reg [31:0] line_t [0:H-1];
  reg [31:0] ymin, ylog = 32'd0;
  integer e2;
  always @(*) begin
    ymin = H;
    for (e2 = 0; e2 < I; e2 = e2 + 1) if (slot_y[32*e2 +: 32] < ymin) ymin = slot_y[32*e2 +: 32];
  end

  always @(posedge clk) begin
    if (!rst && ylog < ymin) begin
      line_t[ylog] = dut_cycles[31:0];
      ylog = ylog + 32'd1;
    end
    if (!rst && !done && ((&slot_done) || (|dut_overflow))) begin
      cycles <= dut_cycles[31:0];
      overflow <= |dut_overflow;
      frames_ok <= all_frames;
      proto_at_end <= proto_errors;
      done <= 1'b1;
    end
  end

  final begin
    $writememh(fout, frame);
    if (log_lines) $writememh(flines, line_t);
    if (has_meta) begin
      fd = $fopen(fmeta, "w");
      $fdisplay(fd, "{\"overflow\": %0d, \"frames_ok\": %0d, \"proto_errors\": %0d}", overflow, frames_ok,
                proto_at_end);
      $fclose(fd);
    end
  end
endmodule
