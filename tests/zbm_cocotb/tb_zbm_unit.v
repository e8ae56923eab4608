// Bench wrapper for a chain of ZB/M units (`zbm_chain_flat`, written by rasterhw.sim.zbm
// around the generated `zbm_unit` Verilog; unit 0 is the head of the merge chain).
//
// No Python in the inner loop: two Verilog-side clocks (segment clock `clk`, merge clock
// `mclk`, half periods SYNC_HALF / MERGE_HALF ns), the edge-pair words of every unit
// preloaded with $readmemh and played into the units' input streams with the idle gaps
// stored beside each word, every merge output slot drained with seeded random
// back-pressure into a frame memory (screen order), then dumped with $writememh.
//
// Stimulus word (hex, one per line): {gap[GW-1:0], word[167:0]}: word = the 168-bit loader
// word (golden_model/zbm/formats.py), raised `gap` clocks after the previous transfer.
// Index file: for unit k, two hex lines: first stimulus word, number of words.
// Plusargs: +stim=<file> +index=<file> +out=<file>.
// Output file: W*H lines of 32 hex digits (PIXEL2 = s1:s0), pixel (x, y) at line y*W + x.
// `cycles`: segment-clock cycles (unit 0's counter) when the last merge word was taken.
// The run also ends (early) on the watchdog (`timeout`) or a unit's sticky `overflow`.
module tb_zbm_unit #(
  // interleave (merge slots), units, frame width and height, gap bits, stimulus memory depth
  // (> all words + 1)
  parameter I = 8, U = 1, W = 64, H = 16, GW = 8, SDEPTH = 1024
) (
  output reg finished,
  output reg timeout,
  output reg [31:0] cycles,
  output [31:0] proto_errors,
  output reg frames_ok,
  output reg overflow
);

  // run-time settings (plusargs, so one simulator build serves every clock ratio and pattern):
  // the clocks' (rasterhw_two_clocks, ../harness.v), +stall= 0..256 (ready low
  // when an 8-bit random number is below it; 0 = never), +seed=, +maxcyc= (watchdog)
  integer STALL = 0, SEED = 1;
  integer MAXCYC = 100000000;
  initial begin
    if (!$value$plusargs("stall=%d", STALL)) STALL = 0;
    if (!$value$plusargs("seed=%d", SEED)) SEED = 1;
    if (!$value$plusargs("maxcyc=%d", MAXCYC)) MAXCYC = 100000000;
  end
  wire clk, mclk;
  rasterhw_two_clocks clocks (.clk(clk), .mclk(mclk));

  reg [8*512-1:0] fout;
  initial begin
    finished = 1'b0;
    timeout = 1'b0;
    cycles = 32'd0;
    frames_ok = 1'b0;
    overflow = 1'b0;
    if (!$value$plusargs("out=%s", fout)) $fatal(1, "tb_zbm_unit: +out= missing");
  end

  wire rst, mrst;
  rasterhw_reset #(.CYCLES(6), .DELAY(0.5)) seg_reset (.clk(clk), .rst(rst));
  rasterhw_reset #(.CYCLES(6), .DELAY(0.5)) merge_reset (.clk(mclk), .rst(mrst));

  // --- the units, their players and the merge-slot sinks ------------------------------------
  wire [I-1:0] slot_done;
  wire [32*I-1:0] slot_y;
  reg all_frames;
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
  wire [31:0] cycles0 = dut_cycles[31:0];
  wire any_overflow = |dut_overflow;

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
      wire r = !mrst && (lf[7:0] >= STALL);
      wire [MW-1:0] p = o_payload[c*MW +: MW];
      assign o_ready[c] = r;
      assign slot_done[c] = (y == H);
      assign slot_y[32*c +: 32] = y;
      assign faddr[32*c +: 32] = y * W + q * I + c;
      always @(posedge mclk) begin
        if (mrst) begin
          lf <= 32'h9E3779B9 ^ (SEED * 32'd7919 + c * 32'd104729 + 32'd1);
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

  reg [31:0] proto_sum;
  assign proto_errors = proto_sum;
  integer e;
  always @(*) begin
    proto_sum = 32'd0;
    for (e = 0; e < U; e = e + 1) proto_sum = proto_sum + in_err[32*e +: 32];
    for (e = 0; e < I; e = e + 1) proto_sum = proto_sum + out_err[32*e +: 32];
    all_frames = 1'b1;
    for (e = 0; e < U; e = e + 1) all_frames = all_frames && (dut_frames[16*e +: 16] == 16'd1);
  end

  // --- per-line log (optional, +lines=FILE): line_t[y] = unit 0's segment-clock count in the
  // merge cycle in which the last chip slot finished merge output line y (steady-state timing).
  reg [31:0] line_t [0:H-1];
  reg [8*512-1:0] flines;
  reg log_lines;
  reg [31:0] ymin, ylog;
  integer e2;
  initial begin
    log_lines = $value$plusargs("lines=%s", flines);
    ylog = 32'd0;
  end
  always @(*) begin
    ymin = H;
    for (e2 = 0; e2 < I; e2 = e2 + 1) if (slot_y[32*e2 +: 32] < ymin) ymin = slot_y[32*e2 +: 32];
  end

  // --- completion ---------------------------------------------------------------------------
  always @(posedge mclk) begin
    // blocking: the dump below, in the same clock edge, must see the last line's entry
    if (!mrst && ylog < ymin) begin
      line_t[ylog] = cycles0;
      ylog = ylog + 32'd1;
    end
    if (!mrst && !finished && ((&slot_done) || timeout || any_overflow)) begin
      cycles <= cycles0;
      overflow <= any_overflow;
      frames_ok <= all_frames;
      $writememh(fout, frame);
      if (log_lines) $writememh(flines, line_t);
      finished <= 1'b1;
    end
  end

  always @(posedge clk) begin
    if (!rst && !finished && cycles0 >= MAXCYC) begin
      timeout <= 1'b1;
    end
  end
endmodule
