// The read-out phase both plain sparse benches share (`include`d as an item of their `case (phase)`;
// each declares localparam READOUT (this phase's number), AW (address bits), the registers raddr
// [AW+1:0] and rd [AW-1:0] (the block's read address) and outmem): the read address is registered
// here and the read port has one cycle of latency, so the word for raddr - 2 arrives now; then the
// next phase.
      READOUT: begin
        if (raddr >= 2) outmem[raddr - 2] <= {rd_tri, rd_z};
`ifdef RASTERHW_RGB
        if (raddr >= 2) outrgb[raddr - 2] <= rd_rgb;  // a bench that defines it declares outrgb, rd_rgb
`endif
        rd <= raddr[AW-1:0];
        raddr <= raddr + 1;
        if (raddr == (1 << AW) + 1) phase <= READOUT + 1;
      end
