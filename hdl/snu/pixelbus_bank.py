"""One bank controller of the SNU pixel-bus controller (Z comparator + double-buffered RGB)."""

from __future__ import annotations

from amaranth import ClockSignal, Instance, Module, Mux, Signal, unsigned
from amaranth.lib import data, enum, memory, stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.utils import ceil_log2
from rasterhw.golden_model.snu.formats import (
    FRAME_HEIGHT,
    FRAME_WIDTH,
    MEM_CYCLE,
    N_BANKS,
    RGB_BITS,
    Z_BITS,
)
from rasterhw.hdl.params import params

__all__ = ["RAM_KINDS", "RAM_VERILOG", "Command", "PixelBusBank", "bank_write_layout"]

RAM_KINDS = ("auto", "memory", "verilog")
#: ``ram="auto"`` uses an Amaranth Memory up to this many words per bank, the Verilog RAM
#: model above (Amaranth writes every initial word of a Memory into the netlist: at the
#: full 1280x1024 frame that is ~115 MB of Verilog and minutes of generation)
AUTO_RAM_DEPTH = 4096
#: words per bank of the full SNU frame (1280 x 1024 over 5 banks), the default depth
FULL_BANK_DEPTH = -(-FRAME_WIDTH * FRAME_HEIGHT // N_BANKS)


def resolve_ram(ram: str, depth: int) -> str:
    """``"auto"`` -> ``"memory"`` for banks of at most :data:`AUTO_RAM_DEPTH` words, else
    ``"verilog"``; any other kind unchanged."""
    return ("memory" if depth <= AUTO_RAM_DEPTH else "verilog") if ram == "auto" else ram

# One write port, read port 0 with enable (Z compare), read port 1 (read-back); both
# read ports synchronous and not transparent (old data on a same-clock write), data
# registers start at 0, contents start at 0 -- exactly lib.memory.Memory(init=[]) as used
# below.
RAM_VERILOG = """\
module rasterhw_pixelbus_ram #(parameter WIDTH = 24, parameter DEPTH = 16, parameter ABITS = 4) (
  input wire clk,
  input wire [ABITS-1:0] wr_addr,
  input wire [WIDTH-1:0] wr_data,
  input wire wr_en,
  input wire [ABITS-1:0] rd0_addr,
  input wire rd0_en,
  output reg [WIDTH-1:0] rd0_data,
  input wire [ABITS-1:0] rd1_addr,
  output reg [WIDTH-1:0] rd1_data
);
  reg [WIDTH-1:0] mem [0:DEPTH-1];
  integer i;
  initial begin
    for (i = 0; i < DEPTH; i = i + 1) mem[i] = {WIDTH{1'b0}};
    rd0_data = {WIDTH{1'b0}};
    rd1_data = {WIDTH{1'b0}};
  end
  always @(posedge clk) begin
    if (wr_en) mem[wr_addr] <= wr_data;
    if (rd0_en) rd0_data <= mem[rd0_addr];
    rd1_data <= mem[rd1_addr];
  end
endmodule
"""


class Command(enum.Enum, shape=1):
    """Frame-buffer commands, applied when every memory cycle in flight has finished."""

    CLEAR = 0  # Z := 0 (far), draw-buffer RGB := 0 (black); one word per clock
    SWAP = 1  # exchange draw and display RGB buffers; one clock


def bank_write_layout(addr_bits: int, z_bits: int) -> data.StructLayout:
    """Payload of a pixel write: ``addr`` (bank-local or linear), ``rgb``, ``z``."""
    return data.StructLayout(
        {
            "addr": unsigned(addr_bits),  # word address
            "rgb": unsigned(RGB_BITS),  # r << 16 | g << 8 | b
            "z": unsigned(z_bits),  # 0 = far; a larger value is nearer
        }
    )


def check_bank_params(*, z_bits: int, mem_cycle: int, ram: str) -> None:
    """Raise ``ValueError`` for bank parameters the controller cannot take (shared with
    ``PixelBus``, which checks them before it builds its banks in ``elaborate``)."""
    if not isinstance(z_bits, int) or not 1 <= z_bits <= 32:
        raise ValueError(f"z_bits must be an integer in 1..32, not {z_bits!r}")
    if not isinstance(mem_cycle, int) or mem_cycle < 2:
        raise ValueError(f"mem_cycle must be an integer >= 2, not {mem_cycle!r}")
    if ram not in RAM_KINDS:
        raise ValueError(f"ram must be one of {', '.join(RAM_KINDS)}, not {ram!r}")


@params("depth", "z_bits", "mem_cycle", "addr_bits", "ram")
class PixelBusBank(wiring.Component):
    """One bank: read stored Z, compare, write RGB+Z when the bus Z is strictly larger.

    A memory cycle lasts ``mem_cycle`` clocks (5: a 400 ns memory against 80 ns bus
    slots).  The accepted write's Z is read in the accept cycle (synchronous read
    port), compared and written in the next one; the bank then stays busy until
    ``mem_cycle`` clocks after the accept, modelling the memory's cycle time.

    Parameters
    ----------
    depth : int
        Words per bank (pixels held by this bank); default a fifth of the 1280 x 1024 frame.
    z_bits : int
        Width of Z (24 in the SNU system).
    mem_cycle : int
        Clocks per memory cycle, >= 2 (read-compare-write needs two clocks).
    ram : str
        ``"auto"`` (default): ``"memory"`` up to :data:`AUTO_RAM_DEPTH` words, else ``"verilog"``;
        ``"memory"``: ``amaranth.lib.memory.Memory`` (pysim and small Verilog);
        ``"verilog"``: an ``Instance`` of :data:`RAM_VERILOG` (``rasterhw_pixelbus_ram``),
        same behaviour, for full-size Verilog -- Amaranth writes every word of a
        ``Memory``'s initial value into the netlist (120 MB and ~5 min at 1280x1024).

    Members
    -------
    i : In(stream.Signature(bank_write_layout(ceil_log2(depth), z_bits)))
        Pixel writes (local address).  ``ready`` is low while the bank is busy or a
        command is offered (commands win), so writes are held back, never dropped.
    i_cmd : In(stream.Signature(Command))
        Commands; accepted when the bank is not busy.  ``CLEAR`` keeps the bank busy for
        ``depth`` clocks after the accept; ``SWAP`` takes effect in the next clock.
    rd_addr : In(ceil_log2(depth)), rd_buf : In(1)
        Read-back address and buffer (0 = draw buffer, 1 = display buffer).
    rd_rgb : Out(RGB_BITS), rd_z : Out(z_bits)
        Read-back data, one clock after ``rd_addr``/``rd_buf``.  Independent of the
        write path (a separate read port, as the VRAM's serial/display port).
    busy : Out(1)
        A memory cycle or a clear is in progress.
    draw_buf : Out(1)
        Physical RGB buffer (0/1) currently being drawn into.

    Throughput: one write per ``mem_cycle`` clocks.  Latency: the write is visible to
    the read-back port two clocks after its accept.
    """

    def __init__(self, *, depth: int = FULL_BANK_DEPTH, z_bits: int = Z_BITS, mem_cycle: int = MEM_CYCLE,
                 ram: str = "auto") -> None:
        if not isinstance(depth, int) or isinstance(depth, bool) or depth < 1:
            raise ValueError(f"depth must be a positive integer, not {depth!r}")
        check_bank_params(z_bits=z_bits, mem_cycle=mem_cycle, ram=ram)
        ram = resolve_ram(ram, depth)
        self._depth = depth
        self._ram = ram
        self._z_bits = z_bits
        self._mem_cycle = mem_cycle
        self._addr_bits = max(1, ceil_log2(depth))
        super().__init__(
            {
                "i": In(stream.Signature(bank_write_layout(self._addr_bits, z_bits))),
                "i_cmd": In(stream.Signature(Command)),
                "rd_addr": In(self._addr_bits),
                "rd_buf": In(1),
                "rd_rgb": Out(RGB_BITS),
                "rd_z": Out(z_bits),
                "busy": Out(1),
                "draw_buf": Out(1),
            }
        )

    def extra_verilog(self) -> str:
        """Hand-written Verilog this block instantiates (the RAM model when ``ram="verilog"``; the
        pixel bus, ``PixelBus``, shares this method)."""
        return RAM_VERILOG if self._ram == "verilog" else ""

    def elaborate(self, platform):
        m = Module()

        rams = {}
        for name, width in (("zmem", self._z_bits), ("rgb0", RGB_BITS), ("rgb1", RGB_BITS)):
            rams[name] = _ram(m, name, width=width, depth=self._depth, addr_bits=self._addr_bits, ram=self._ram)
        zmem = rams["zmem"]
        rgb = [rams["rgb0"], rams["rgb1"]]

        count = Signal(range(self._mem_cycle))  # clocks left in the memory cycle
        clearing = Signal()
        clr_addr = Signal(range(self._depth))
        draw = Signal()  # physical buffer drawn into; the other one is displayed
        pending = Signal()  # compare/write clock of an accepted write
        w_addr = Signal(self._addr_bits)
        w_rgb = Signal(RGB_BITS)
        w_z = Signal(self._z_bits)

        m.d.comb += [
            self.busy.eq((count != 0) | clearing),
            self.draw_buf.eq(draw),
            self.i_cmd.ready.eq(~self.busy),
            self.i.ready.eq(~self.busy & ~self.i_cmd.valid),
        ]

        accept = Signal()
        m.d.comb += [
            accept.eq(self.i.valid & self.i.ready),
            zmem.rd0_addr.eq(self.i.payload.addr),
            zmem.rd0_en.eq(accept),
        ]
        m.d.sync += pending.eq(accept)
        with m.If(accept):
            m.d.sync += [
                count.eq(self._mem_cycle - 1),
                w_addr.eq(self.i.payload.addr),
                w_rgb.eq(self.i.payload.rgb),
                w_z.eq(self.i.payload.z),
            ]
        with m.Elif(count != 0):
            m.d.sync += count.eq(count - 1)

        # Compare against the stored Z one clock after the accept; write only if nearer.
        write = Signal()
        m.d.comb += write.eq(pending & (w_z > zmem.rd0_data))

        with m.If(self.i_cmd.valid & self.i_cmd.ready):
            with m.Switch(self.i_cmd.payload):
                with m.Case(Command.CLEAR):
                    m.d.sync += [clearing.eq(1), clr_addr.eq(0)]
                with m.Case(Command.SWAP):
                    m.d.sync += draw.eq(~draw)
        with m.If(clearing):
            m.d.sync += clr_addr.eq(clr_addr + 1)
            with m.If(clr_addr == self._depth - 1):
                m.d.sync += clearing.eq(0)

        m.d.comb += [
            zmem.wr_addr.eq(Mux(clearing, clr_addr, w_addr)),
            zmem.wr_data.eq(Mux(clearing, 0, w_z)),
            zmem.wr_en.eq(write | clearing),
        ]
        for k in range(2):
            m.d.comb += [
                rgb[k].wr_addr.eq(Mux(clearing, clr_addr, w_addr)),
                rgb[k].wr_data.eq(Mux(clearing, 0, w_rgb)),
                rgb[k].wr_en.eq((write | clearing) & (draw == k)),
                rgb[k].rd0_en.eq(0),
            ]

        # Read-back: physical buffer = draw ^ rd_buf, selected one clock later.
        phys = Signal()
        m.d.sync += phys.eq(draw ^ self.rd_buf)
        for r in (zmem, *rgb):
            m.d.comb += r.rd1_addr.eq(self.rd_addr)
        m.d.comb += [
            self.rd_z.eq(zmem.rd1_data),
            self.rd_rgb.eq(Mux(phys, rgb[1].rd1_data, rgb[0].rd1_data)),
        ]
        return m


def bank_ram_signature(width: int, addr_bits: int) -> wiring.Signature:
    """One bank RAM as the bank controller sees it: a write port and two synchronous read
    ports (port 0 with an enable, port 1 always reading)."""
    return wiring.Signature({
        "wr_addr": In(addr_bits), "wr_data": In(width), "wr_en": In(1),
        "rd0_addr": In(addr_bits), "rd0_en": In(1), "rd0_data": Out(width),
        "rd1_addr": In(addr_bits), "rd1_data": Out(width),
    })


class _BankRamMemory(wiring.Component):
    """:func:`bank_ram_signature` on an Amaranth ``Memory`` (pysim, small frames)."""

    def __init__(self, width: int, depth: int, addr_bits: int) -> None:
        self._width, self._depth = width, depth
        super().__init__(bank_ram_signature(width, addr_bits))

    def elaborate(self, platform):
        m = Module()
        m.submodules.mem = mem = memory.Memory(shape=unsigned(self._width), depth=self._depth, init=[])
        wr, rd0, rd1 = mem.write_port(), mem.read_port(), mem.read_port()
        m.d.comb += [
            wr.addr.eq(self.wr_addr), wr.data.eq(self.wr_data), wr.en.eq(self.wr_en),
            rd0.addr.eq(self.rd0_addr), rd0.en.eq(self.rd0_en), self.rd0_data.eq(rd0.data),
            rd1.addr.eq(self.rd1_addr), self.rd1_data.eq(rd1.data),
        ]
        return m


class _BankRamVerilog(wiring.Component):
    """:func:`bank_ram_signature` on the hand-written :data:`RAM_VERILOG` model (large frames:
    no multi-megabyte initial value in the netlist)."""

    def __init__(self, width: int, depth: int, addr_bits: int) -> None:
        self._width, self._depth, self._addr_bits = width, depth, addr_bits
        super().__init__(bank_ram_signature(width, addr_bits))

    def elaborate(self, platform):
        m = Module()
        m.submodules.ram = Instance(
            "rasterhw_pixelbus_ram",
            p_WIDTH=self._width, p_DEPTH=self._depth, p_ABITS=self._addr_bits,
            i_clk=ClockSignal(),
            i_wr_addr=self.wr_addr, i_wr_data=self.wr_data, i_wr_en=self.wr_en,
            i_rd0_addr=self.rd0_addr, i_rd0_en=self.rd0_en, o_rd0_data=self.rd0_data,
            i_rd1_addr=self.rd1_addr, o_rd1_data=self.rd1_data,
        )
        return m


def _ram(m: Module, name: str, *, width: int, depth: int, addr_bits: int, ram: str) -> wiring.Component:
    r = (_BankRamMemory if ram == "memory" else _BankRamVerilog)(width, depth, addr_bits)
    m.submodules[name] = r
    return r
