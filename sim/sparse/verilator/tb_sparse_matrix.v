// Timing-free Verilator bench for the generated `sparse_matrix` (rasterhw.hdl.sparse.matrix, cells
// instantiated by name: one `sparse_cell` module for every processor).
// Plays the broadcast records of +in= (binary: one BW-bit big-endian word per triangle, +ntri= of
// them; read by tb_sparse_load.vh, shared with tb_sparse_vp) into the matrix with no gaps from the first cycle after reset, with the input FIFOs limited
// to +limit= entries at run time; waits until the matrix is idle; reads every processor's counters
// (stat_cell x stat_sel) and the matrix's frame and stall cycles into +stats=, then sweeps the full
// raster through the interleaved read port and writes {tri, z} per pixel (row-major) to +out=.
// With RASTERHW_RGB defined (a matrix built with colour: the driver's generated
// tb_sparse_matrix_cfg.vh defines it) it also writes each pixel's colour (R | G << 8 | B << 16,
// from the port rd_rgb) to +rgb=.
`include "tb_sparse_matrix_cfg.vh"
module tb_sparse_matrix #(parameter N = 7, parameter LP = 2, parameter LQ = 2, parameter BW = 600,
                          parameter MAXT = 16384, parameter ZW = 25, parameter TW = 16, parameter NS = 18,
                          parameter LIMW = 7, parameter CW = 4, parameter SW = 5)
                         (input clk, output reg done, output reg [31:0] cycles);
  localparam P = 1 << (LP + LQ);
  localparam XW = N + LP;
  localparam YW = N + LQ;
  localparam AW = XW + YW;
  localparam READOUT = 4;
  reg [BW-1:0] rom [0:MAXT-1];
  reg [TW+ZW-1:0] outmem [0:(1 << AW) - 1];
  reg [31:0] stats [0:P * NS + 1];
`ifdef RASTERHW_RGB
  reg [23:0] outrgb [0:(1 << AW) - 1];
  reg [1023:0] rgb_file;
  wire [23:0] rd_rgb;
  initial if (!$value$plusargs("rgb=%s", rgb_file)) rgb_file = "rgb.hex";
`endif
`include "tb_sparse_load.vh"
  integer limit;
  reg [31:0] idx;
  reg rst;
  reg [2:0] phase;  // 0 reset, 1 feed, 2 drain, 3 counters, 4 read-out, 5 done
  reg [AW+1:0] raddr;
  reg [AW-1:0] rd;
  reg [15:0] sc, ss;
  wire busy, i_ready;
  wire [ZW-1:0] rd_z;
  wire [TW-1:0] rd_tri;
  wire [31:0] frame_cycles, stall_cycles, stat;
  initial begin
    if (!$value$plusargs("limit=%d", limit)) limit = 1;
    idx = 0; phase = 0; done = 0; cycles = 0; raddr = 0; rd = 0; rst = 1; sc = 0; ss = 0;
  end
  sparse_matrix dut (.clk(clk), .rst(rst), .i__payload(rom[idx[13:0]]), .i__valid(phase == 1 && idx < ntri),
                     .i__ready(i_ready), .limit(limit[LIMW-1:0]), .rd_x(rd[XW-1:0]), .rd_y(rd[AW-1:XW]),
                     .rd_z(rd_z), .rd_tri(rd_tri), .busy(busy), .cycles(frame_cycles), .stall_cycles(stall_cycles),
                     .stat_cell(sc[CW-1:0]), .stat_sel(ss[SW-1:0]), .stat(stat)
`ifdef RASTERHW_RGB
                     , .rd_rgb(rd_rgb)
`endif
                     );

  always @(posedge clk) begin
    case (phase)
      0: begin rst <= 0; phase <= 1; end
      1: begin
        cycles <= cycles + 1;
        if (idx < ntri && i_ready) idx <= idx + 1;
        if (idx >= ntri) phase <= 2;
      end
      2: begin
        cycles <= cycles + 1;
        if (!busy) phase <= 3;
      end
      3: begin  // stat is combinational from stat_cell / stat_sel
        stats[2 + sc * NS + ss] <= stat;
        if (ss == NS - 1) begin
          ss <= 0;
          sc <= sc + 1;
          if (sc == P - 1) phase <= 4;
        end else ss <= ss + 1;
      end
`include "tb_sparse_readout.vh"
      5: done <= 1;
    endcase
  end
  final begin
    stats[0] = frame_cycles;
    stats[1] = stall_cycles;
    $writememh(out_file, outmem);
    $writememh(stats_file, stats);
`ifdef RASTERHW_RGB
    $writememh(rgb_file, outrgb);
`endif
  end
endmodule
