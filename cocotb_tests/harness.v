// The Verilog side of the verification harness, shared by every bench wrapper
// (cocotb_tests/*/tb_*.v and the plain-Verilator mains):
//
//   rasterhw_two_clocks    the segment and merge clocks, half periods and phase from plusargs
//   rasterhw_reset         holds a reset for CYCLES rising edges of its own clock, then releases
//                          it DELAY ns after the next edge (away from every clock edge)
//   rasterhw_stream_source plays words preloaded from a file (name from a plusarg; $readmemh, or
//                          $fread of big-endian binary words) into a stream, each after its idle
//                          gap, `repeats` times, stream rules kept; the generic bench's source
//                          and every hand-written bench's player
//   rasterhw_stream_player the same with the older port list (no count plusarg, hex only): a
//                          name kept for the benches that still use it
//   rasterhw_stream_check  counts stream-rule violations and transfers on one port
//   rasterhw_stream_sink   takes words with seeded back-pressure (the xorshift of xorshift.vh),
//                          stamps and dumps them (the generic bench)
//
// Stimulus word: {gap[GW-1:0], payload[PW-1:0]}: the payload is offered `gap` clocks after the
// clock following the previous transfer (the first `gap` clocks after reset) and held until
// accepted.

// +sync_half= / +merge_half= ns (default 5) and +merge_phase= ns (default 1), so one simulator
// build serves every clock ratio. Equal clocks in phase (+merge_phase=0, the speed runs) toggle
// in one process: one coroutine resumption per edge instead of two.
module rasterhw_two_clocks (
  output reg clk,
  output reg mclk
);
  integer SYNC_HALF = 5, MERGE_HALF = 5, MERGE_PHASE = 1;
  initial begin
    clk = 1'b0;
    mclk = 1'b0;
    if (!$value$plusargs("sync_half=%d", SYNC_HALF)) SYNC_HALF = 5;
    if (!$value$plusargs("merge_half=%d", MERGE_HALF)) MERGE_HALF = 5;
    if (!$value$plusargs("merge_phase=%d", MERGE_PHASE)) MERGE_PHASE = 1;
  end
  wire one_clock = (MERGE_PHASE == 0) && (MERGE_HALF == SYNC_HALF);
  initial begin
    #1;  // let the plusargs be read first
    if (one_clock)
      forever begin
        #(SYNC_HALF);
        clk = ~clk;
        mclk = ~mclk;
      end
    else
      forever #(SYNC_HALF) clk = ~clk;
  end
  initial begin
    #1;
    if (!one_clock) begin
      #(MERGE_PHASE);
      forever #(MERGE_HALF) mclk = ~mclk;
    end
  end
endmodule

// Each reset is released by a process that counts only its own clock's edges, DELAY ns after a
// rising edge of that clock: before its falling edge (half periods are >= 1 ns) and away from
// every edge of any other clock (edges fall on whole ns). Python stream monitors sample at the
// falling edge, so they see the same reset value as the design's next rising edge. (A
// non-blocking release at the edge itself is not used: Verilator --timing and Icarus then
// disagree by one cycle on when the flops see it.)
module rasterhw_reset #(
  parameter CYCLES = 6,
  parameter real DELAY = 0.5
) (
  input wire clk,
  output reg rst
);
  initial begin
    rst = 1'b1;
    repeat (CYCLES) @(posedge clk);
    #(DELAY) rst = 1'b0;
  end
endmodule

// The older port list of rasterhw_stream_source (hex file, `count` from the port): kept so the
// benches that instantiate it by this name keep working.
module rasterhw_stream_player #(
  parameter PW = 8,                // payload bits
  parameter GW = 8,                // gap bits
  parameter DEPTH = 16,            // words the memory holds (> the words played + 1)
  parameter FILE_ARG = "stim=%s"   // plusarg naming the $readmemh file
) (
  input wire clk,
  input wire rst,
  input wire [31:0] base,          // first word played
  input wire [31:0] count,         // words per repetition
  input wire [31:0] repeats,       // repetitions (1 = play once)
  output wire valid,
  input wire ready,
  output wire [PW-1:0] payload,
  output wire done                 // every repetition played
);
  rasterhw_stream_source #(.PW(PW), .GW(GW), .DEPTH(DEPTH), .FILE_ARG(FILE_ARG), .COUNT_FROM_ARG(0)) source (
    .clk(clk), .rst(rst), .base(base), .count(count), .repeats(repeats),
    .valid(valid), .ready(ready), .payload(payload), .done(done));
endmodule

// Once a clock has `valid` high and `ready` low, the next clock must keep `valid` high and the
// same payload ("raise valid without waiting for ready; hold the payload until accepted").
// `errors` counts violating clocks, `transfers` counts accepted words. In Verilog so it costs
// nothing at speed; the cocotb tests also run the Python checker of cocotb_tests/common.py.
module rasterhw_stream_check #(
  parameter PW = 128
) (
  input clk,
  input rst,
  input valid,
  input ready,
  input [PW-1:0] payload,
  output reg [31:0] errors,
  output reg [31:0] transfers
);
  reg held;
  reg [PW-1:0] held_payload;
  initial begin
    errors = 32'd0;
    transfers = 32'd0;
    held = 1'b0;
  end
  always @(posedge clk) begin
    if (rst) begin
      held <= 1'b0;
    end else begin
      if (held && (!valid || payload != held_payload)) errors <= errors + 32'd1;
      if (valid && ready) transfers <= transfers + 32'd1;
      held <= valid && !ready;
      held_payload <= payload;
    end
  end
endmodule

// ---------------------------------------------------------------------------------------------
// The generic bench (sim/engines/verilator.py): one stream source per input port of a block and
// one stream sink per output port, in a bench top generated from Amaranth around the block.

// Plays words {gap[GW-1:0], payload[PW-1:0]} from the file named by the plusarg FILE_ARG: each word
// is offered `gap` clocks after the clock of the previous transfer (the first `gap` clocks after
// start or reset) and held until accepted (the stream rules); the words base .. base + count - 1,
// `repeats` times; `done` once every repetition was taken. The file is $readmemh text, or with
// BINARY = 1 big-endian binary words of (GW + PW) / 8 bytes read with $fread (no text to parse:
// a $readmemh of 10 million words takes longer than simulating them). The word count comes from
// the plusarg COUNT_ARG (COUNT_FROM_ARG = 1, the generic bench: a count of 0 needs no file) or
// from the `count` port (COUNT_FROM_ARG = 0). Without `rst` (tied low) the source starts from its
// initial values at time 0 (the generic bench); a bench with a reset restarts it there.
module rasterhw_stream_source #(
  parameter PW = 8,
  parameter GW = 8,
  parameter DEPTH = 16,              // > words played
  parameter FILE_ARG = "i=%s",
  parameter COUNT_ARG = "i_n=%d",
  parameter COUNT_FROM_ARG = 1,
  parameter BINARY = 0
) (
  input wire clk,
  input wire rst,
  input wire [31:0] base,            // first word played
  input wire [31:0] count,           // words per repetition (COUNT_FROM_ARG = 0)
  input wire [31:0] repeats,         // repetitions (1 = play once)
  output wire valid,
  input wire ready,
  output wire [PW-1:0] payload,
  output wire done
);
  reg [GW+PW-1:0] mem [0:DEPTH-1];
  reg [8*512-1:0] fname;
  reg [31:0] n_arg, ptr, rep;
  reg [GW-1:0] wt;
  integer fd, got;
  initial begin
    if (COUNT_FROM_ARG == 0 || !$value$plusargs(COUNT_ARG, n_arg)) n_arg = 0;
    if (COUNT_FROM_ARG == 0 || n_arg != 0) begin
      if (!$value$plusargs(FILE_ARG, fname)) $fatal(1, "rasterhw_stream_source: +%s missing", FILE_ARG);
      if (BINARY != 0) begin
        fd = $fopen(fname, "rb");
        if (fd == 0) $fatal(1, "rasterhw_stream_source: cannot open %0s", fname);
        got = $fread(mem, fd);
        $fclose(fd);
      end else begin
        $readmemh(fname, mem);
      end
    end
    ptr = 0;
    rep = 0;
    wt = (COUNT_FROM_ARG == 0 || n_arg != 0) ? mem[0][GW+PW-1:PW] : {GW{1'b0}};
  end
  wire [31:0] n = (COUNT_FROM_ARG != 0) ? n_arg : count;
  wire last = (ptr + 32'd1 == n);
  wire [GW+PW-1:0] cur = mem[base + ptr];
  wire [GW+PW-1:0] nxt = mem[base + (last ? 32'd0 : ptr + 32'd1)];
  assign done = (rep >= repeats) || (n == 32'd0);
  assign valid = !rst && !done && (wt == {GW{1'b0}});
  assign payload = cur[PW-1:0];
  always @(posedge clk) begin
    if (rst) begin
      ptr <= 32'd0;
      rep <= 32'd0;
      wt <= mem[base][GW+PW-1:PW];
    end else if (valid && ready) begin
      ptr <= last ? 32'd0 : ptr + 32'd1;
      if (last) rep <= rep + 32'd1;
      wt <= nxt[GW+PW-1:PW];
    end else if (wt != {GW{1'b0}}) begin
      wt <= wt - 1'b1;
    end
  end
endmodule

// Takes words from a stream: `ready` is low on a clock when the low byte of a seeded xorshift
// (+NAME_seed=, advanced every clock) is below +NAME_stall= (0 = always ready). Every transfer's
// payload and the `cycle` it happened in are stored and dumped at the end ($writememh to +NAME=
// and +NAME_cyc=); `done` once +NAME_n= words were taken. With +dump_bin=1 (a simulator with
// `final` blocks: the plain Verilator engine) the dumps are binary instead: the words taken, each
// `$fwrite` "%u" (little-endian, in 4-byte units: 4 * ceil(PW / 32) bytes a word; a stamp 4 bytes),
// read with np.fromfile (sim/engines/verilator.py collected).
module rasterhw_stream_sink #(
  parameter PW = 8,
  parameter DEPTH = 16,
  parameter FILE_ARG = "o=%s",
  parameter CYC_ARG = "o_cyc=%s",
  parameter COUNT_ARG = "o_n=%d",
  parameter STALL_ARG = "o_stall=%d",
  parameter SEED_ARG = "o_seed=%d"
) (
  input wire clk,
  input wire [31:0] cycle,
  input wire valid,
  output wire ready,
  input wire [PW-1:0] payload,
  output wire done
);
  reg [PW-1:0] words [0:DEPTH-1];
  reg [31:0] stamps [0:DEPTH-1];
  reg [8*512-1:0] fwords, fcyc;
  reg [31:0] n, q, stall, seed, lf, bin;
  initial begin
    if (!$value$plusargs("dump_bin=%d", bin)) bin = 0;
    if (!$value$plusargs(COUNT_ARG, n)) n = 0;
    if (!$value$plusargs(STALL_ARG, stall)) stall = 0;
    if (!$value$plusargs(SEED_ARG, seed)) seed = 1;
    if (!$value$plusargs(FILE_ARG, fwords)) fwords = 0;
    if (!$value$plusargs(CYC_ARG, fcyc)) fcyc = 0;
    q = 0;
    lf = seed;
  end
`ifndef RASTERHW_NO_FINAL
  // binary: CH words a $fwrite, each zero-extended to whole 4-byte units, so the bytes are those
  // of CH one-word "%u" writes (Verilator's cost is per call: one word a call cost as much as the
  // $writememh text, ~0.4 CPU-s for the 1.3 M-pixel frame of `sim pixelbus`)
  localparam CH = 64;
  localparam W32 = 32 * ((PW + 31) / 32);
  reg [CH*W32-1:0] wchunk;
  reg [CH*32-1:0] cchunk;
  integer fd, i, j;
  final begin
    if (bin != 0) begin
      if (fwords != 0) begin
        fd = $fopen(fwords, "wb");
        for (i = 0; i + CH <= q; i = i + CH) begin
          for (j = 0; j < CH; j = j + 1) wchunk[j*W32 +: W32] = W32'(words[i+j]);
          $fwrite(fd, "%u", wchunk);
        end
        for (; i < q; i = i + 1) $fwrite(fd, "%u", words[i]);
        $fclose(fd);
      end
      if (fcyc != 0) begin
        fd = $fopen(fcyc, "wb");
        for (i = 0; i + CH <= q; i = i + CH) begin
          for (j = 0; j < CH; j = j + 1) cchunk[j*32 +: 32] = stamps[i+j];
          $fwrite(fd, "%u", cchunk);
        end
        for (; i < q; i = i + 1) $fwrite(fd, "%u", stamps[i]);
        $fclose(fd);
      end
    end else begin
      if (fwords != 0) $writememh(fwords, words, 0, (q == 0) ? 0 : q - 1);
      if (fcyc != 0) $writememh(fcyc, stamps, 0, (q == 0) ? 0 : q - 1);
    end
  end
`else
  // a Verilog-2005 simulator (Icarus at -g2005: at -g2012 it no longer runs the initial-value
  // trigger of yosys's `always @*` processes): no `final`; the dumps are written on the first
  // rising edge at which the sink is done (the cocotb engine's test gives every clock one more)
  reg dumped = 1'b0;
  always @(posedge clk) begin
    if (done && !dumped) begin
      if (fwords != 0) $writememh(fwords, words, 0, (q == 0) ? 0 : q - 1);
      if (fcyc != 0) $writememh(fcyc, stamps, 0, (q == 0) ? 0 : q - 1);
      dumped <= 1'b1;
    end
  end
`endif
  // the 32-bit xorshift; sim/engines/pattern.py draws the same sequence for the pysim engine
`include "xorshift.vh"
  assign ready = ({24'd0, lf[7:0]} >= stall);
  assign done = (q >= n);
  always @(posedge clk) begin
    lf <= xorshift32(lf);
    if (valid && ready && q < DEPTH) begin
      words[q] <= payload;
      stamps[q] <= cycle;
      q <= q + 32'd1;
    end
  end
endmodule
