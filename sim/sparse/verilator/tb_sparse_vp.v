// Timing-free Verilator bench for the generated `sparse_vp` (rasterhw.hdl.sparse.vp).
// Plays the broadcast records of +in= (binary: one BW-bit big-endian word per triangle, +ntri= of them;
// read by tb_sparse_load.vh, shared with tb_sparse_matrix) into
// processor (+a=, +b=) -- with no gaps, or (+idle=K, 1..255, +seed=S) with random idle clocks:
// a record not yet offered is offered only when a seeded 8-bit xorshift number is >= K, and an
// offered one is held until taken (the stream rules) -- waits until the processor is idle, then sweeps the local
// memory's read port and writes {tri, z} per sparse pixel to +out= and the per-level tests,
// stalls and the cycle count to +stats= (hex words).
module tb_sparse_vp #(parameter N = 7, parameter BW = 600, parameter MAXT = 16384, parameter ZW = 25,
                      parameter TW = 16) (input clk, output reg done, output reg [31:0] cycles);
  reg [BW-1:0] rom [0:MAXT-1];
  reg [TW+ZW-1:0] outmem [0:(1 << (2 * N)) - 1];
  reg [31:0] stats [0:2 * N + 1];
`include "tb_sparse_load.vh"
  integer pa, pb, i, IDLE, SEED;
  reg offer;
  reg [31:0] lf;
  reg [31:0] idx;
  reg rst;
  localparam AW = 2 * N;
  localparam READOUT = 3;
  reg [2:0] phase;  // 0 reset, 1 feed, 2 drain, 3 read-out, 4 done
  reg [AW+1:0] raddr;
  reg [AW-1:0] rd;
  wire busy, i_ready;
  wire [ZW-1:0] rd_z;
  wire [TW-1:0] rd_tri;
  wire [31:0] writes;
  wire [32 * N - 1:0] tests_v, stalls_v;
  initial begin
    if (!$value$plusargs("a=%d", pa)) pa = 0;
    if (!$value$plusargs("b=%d", pb)) pb = 0;
    if (!$value$plusargs("idle=%d", IDLE)) IDLE = 0;
    if (!$value$plusargs("seed=%d", SEED)) SEED = 1;
    offer = 1; lf = 32'h9E3779B9 ^ (SEED * 32'd7919 + 32'd1);
    idx = 0; phase = 0; done = 0; cycles = 0; raddr = 0; rd = 0; rst = 1;
  end
  sparse_vp dut (.clk(clk), .rst(rst), .a(pa[5:0]), .b(pb[5:0]), .i__payload(rom[idx[13:0]]),
                 .i__valid(phase == 1 && idx < ntri && offer), .i__ready(i_ready), .rd_addr(rd), .rd_z(rd_z),
                 .rd_tri(rd_tri), .writes(writes), .busy(busy)
`include "tb_sparse_vp_ports.vh"
                 );
`include "xorshift.vh"

  always @(posedge clk) begin
    case (phase)
      0: begin rst <= 0; phase <= 1; end
      1: begin
        cycles <= cycles + 1;
        lf <= xorshift32(lf);
        if (!offer || i_ready) offer <= (lf[7:0] >= IDLE);
        if (idx < ntri && offer && i_ready) idx <= idx + 1;
        if (idx >= ntri) phase <= 2;
      end
      2: begin
        cycles <= cycles + 1;
        if (!busy) phase <= 3;
      end
`include "tb_sparse_readout.vh"
      4: done <= 1;
    endcase
  end
  final begin
    for (i = 0; i < N; i = i + 1) begin
      stats[i] = tests_v[32 * i +: 32];
      stats[N + i] = stalls_v[32 * i +: 32];
    end
    stats[2 * N] = cycles;
    stats[2 * N + 1] = writes;
    $writememh(out_file, outmem);
    $writememh(stats_file, stats);
  end
endmodule
