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
  // what the core takes (tb_zbm_unit_core.v): interleave (merge slots), units, frame width and
  // height, gap bits, stimulus memory depth (> all words + 1)
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

  // --- the units, their players and the merge-slot sinks (tb_zbm_unit_core.v) -------------
  wire [I-1:0] slot_done;
  wire [32*I-1:0] slot_y;
  wire [31:0] cycles0;
  wire any_overflow, all_frames;
  tb_zbm_unit_core #(.I(I), .U(U), .W(W), .H(H), .GW(GW), .SDEPTH(SDEPTH)) core (
    .clk(clk), .rst(rst), .mclk(mclk), .mrst(mrst), .stall(STALL), .seed(SEED),
    .slot_done(slot_done), .slot_y(slot_y), .cycles0(cycles0), .any_overflow(any_overflow),
    .all_frames(all_frames), .proto_errors(proto_errors));

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
      $writememh(fout, core.frame);
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
