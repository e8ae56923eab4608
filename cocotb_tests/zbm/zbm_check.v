// Stream-rule checker for the ZB/M benches, in Verilog so that it costs nothing at speed.
//
// Once a clock has `valid` high and `ready` low, the next clock must keep `valid` high and
// the same payload ("raise valid without waiting for ready; hold the payload until
// accepted"). `errors` counts violating clocks, `transfers` counts accepted words.
// (The cocotb tests also run the Python checker of cocotb_tests/common.py on every stream.)
module zbm_stream_check #(
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
