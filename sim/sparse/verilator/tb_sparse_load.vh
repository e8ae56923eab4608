// The set-up both plain sparse benches share (`include`d inside tb_sparse_vp and tb_sparse_matrix,
// which declare `reg [BW-1:0] rom [0:MAXT-1]`): the file names and the record count from the
// plusargs (+in=, +out=, +stats=, +ntri=; the drivers pass all four), and the broadcast records
// read from +in= in binary, one BW-bit big-endian word per triangle (a $readmemh parse of the
// 600-bit records cost more than the run's clock loop).
  reg [1023:0] in_file, out_file, stats_file;
  integer ntri, fd, got;
  initial begin
    if (!$value$plusargs("in=%s", in_file)) in_file = "in.bin";
    if (!$value$plusargs("out=%s", out_file)) out_file = "out.hex";
    if (!$value$plusargs("stats=%s", stats_file)) stats_file = "stats.hex";
    if (!$value$plusargs("ntri=%d", ntri)) ntri = 0;
    if (ntri > 0) begin
      fd = $fopen(in_file, "rb");
      if (fd == 0) $fatal(1, "%m: cannot open %0s", in_file);
      got = $fread(rom, fd);
      $fclose(fd);
      if (got != ntri * ((BW + 7) / 8)) $fatal(1, "%m: %0s holds %0d bytes, not %0d records", in_file, got, ntri);
    end
  end
