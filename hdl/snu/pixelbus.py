"""SNU pixel-bus controller: two pipelines, fixed time slots, 5 interleaved Z-buffer banks."""

from __future__ import annotations

from amaranth import Array, Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out
from amaranth.utils import ceil_log2
from rasterhw.golden_model.snu import formats as F
from rasterhw.hdl.params import params
from rasterhw.hdl.snu.pixelbus_bank import (
    Command,
    PixelBusBank,
    bank_write_layout,
    check_bank_params,
    resolve_ram,
)

__all__ = ["Command", "PixelBus"]


@params("width", "height", "z_bits", "n_banks", "mem_cycle", "bank_depth", "addr_bits", "ram")
class PixelBus(wiring.Component):
    """The pixel bus shared by two geometry pipelines, over a 5-way interleaved frame buffer.

    * Fixed time slots, no arbitration: clock ``t`` belongs to pipeline ``t % 2``
      (``t`` = the ``cycle`` counter, 0 in the first clock after reset).  A slot whose
      owner has nothing valid is wasted.
    * Bank mapping ``bank = addr % n_banks``, ``local = addr // n_banks``: neighbours on
      a scan line fall in successive banks; with a width that is a multiple of 5
      (1280) a vertical line stays in one bank.
    * The owner's write is accepted when its bank is not busy; otherwise the owner's
      ``ready`` stays low (a stall, never a drop) and it retries in its next slot, so
      order within a pipeline is kept.
    * Commands (``i_cmd``: clear, swap) block new pixel grants while offered, and are
      accepted by all banks in the same clock once every bank has finished its memory
      cycle.  Clear takes ``ceil(width*height/n_banks)`` clocks; swap one clock.

    Parameters
    ----------
    width, height : int
        Frame size; linear address ``addr = y * width + x``.  Default 1280 x 1024.
    z_bits : int
        Z width (24); far = 0.
    n_banks : int
        Interleave factor (5).
    mem_cycle : int
        Clocks per bank memory cycle (5 = 400 ns / 80 ns).
    ram : str
        Bank RAM implementation, ``"auto"`` (default: ``"verilog"`` for banks above
        ``AUTO_RAM_DEPTH`` words, so the full frame generates in seconds), ``"memory"`` or
        ``"verilog"`` (see :class:`PixelBusBank`).

    Members
    -------
    i_pipe0, i_pipe1 : In(stream.Signature(bank_write_layout(addr_bits, z_bits)))
        Pixel writes of pipeline 0 and 1, ``addr`` linear.
    i_cmd : In(stream.Signature(Command))
        Frame-buffer commands.
    rd_addr : In(addr_bits), rd_buf : In(1)
        Read-back linear address; 0 = draw buffer, 1 = display buffer.
    rd_rgb : Out(RGB_BITS), rd_z : Out(z_bits)
        Read-back data, one clock later.
    cycle : Out(32)
        Free-running clock counter (bit 0 is the slot owner).
    busy, idle : Out(1)
        Some bank is (is not) in a memory cycle or a clear.
    draw_buf : Out(1)
        Physical RGB buffer drawn into (toggles on swap).

    Throughput: at most one write per clock (12.5 Mpixel/s at 80 ns), reached only
    when both pipelines have a write in every slot and never hit a busy bank.
    """

    def __init__(
        self,
        *,
        width: int = F.FRAME_WIDTH,
        height: int = F.FRAME_HEIGHT,
        z_bits: int = F.Z_BITS,
        n_banks: int = F.N_BANKS,
        mem_cycle: int = F.MEM_CYCLE,
        ram: str = "auto",
    ) -> None:
        for name, v in (("width", width), ("height", height)):
            if not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be a positive integer, not {v!r}")
        if not isinstance(n_banks, int) or n_banks < 1:
            raise ValueError(f"n_banks must be a positive integer, not {n_banks!r}")
        if width * height < n_banks:
            raise ValueError(f"a {width}x{height} frame is smaller than {n_banks} banks")
        check_bank_params(z_bits=z_bits, mem_cycle=mem_cycle, ram=ram)
        self._ram = resolve_ram(ram, -(-width * height // n_banks))
        self._width = width
        self._height = height
        self._z_bits = z_bits
        self._n_banks = n_banks
        self._mem_cycle = mem_cycle
        self._bank_depth = -(-width * height // n_banks)
        self._addr_bits = max(1, ceil_log2(width * height))
        layout = bank_write_layout(self._addr_bits, z_bits)
        super().__init__(
            {
                "i_pipe0": In(stream.Signature(layout)),
                "i_pipe1": In(stream.Signature(layout)),
                "i_cmd": In(stream.Signature(Command)),
                "rd_addr": In(self._addr_bits),
                "rd_buf": In(1),
                "rd_rgb": Out(F.RGB_BITS),
                "rd_z": Out(z_bits),
                "cycle": Out(32),
                "busy": Out(1),
                "idle": Out(1),
                "draw_buf": Out(1),
            }
        )

    @property
    def clear_cycles(self) -> int:
        """Clocks a clear keeps the banks busy after its accept."""
        return self._bank_depth

    extra_verilog = PixelBusBank.extra_verilog

    def elaborate(self, platform):
        m = Module()
        n = self._n_banks
        banks = []
        for b in range(n):
            bank = PixelBusBank(
                depth=self._bank_depth, z_bits=self._z_bits, mem_cycle=self._mem_cycle, ram=self._ram
            )
            m.submodules[f"bank{b}"] = bank
            banks.append(bank)

        m.d.sync += self.cycle.eq(self.cycle + 1)
        slot = self.cycle[0]

        # The slot owner's write goes to its bank; nobody else drives the bus this clock.
        owner = [self.i_pipe0, self.i_pipe1]
        valid = Signal()
        payload = Signal.like(self.i_pipe0.payload)
        with m.If(slot):
            m.d.comb += [valid.eq(self.i_pipe1.valid), payload.eq(self.i_pipe1.payload)]
        with m.Else():
            m.d.comb += [valid.eq(self.i_pipe0.valid), payload.eq(self.i_pipe0.payload)]

        bank_sel = Signal(range(n))
        local = Signal(banks[0].addr_bits)
        m.d.comb += [bank_sel.eq(payload.addr % n), local.eq(payload.addr // n)]

        bank_ready = Array(b.i.ready for b in banks)
        grant = Signal()
        m.d.comb += grant.eq(bank_ready[bank_sel] & ~self.i_cmd.valid)
        for b, bank in enumerate(banks):
            m.d.comb += [
                bank.i.valid.eq(valid & (bank_sel == b) & ~self.i_cmd.valid),
                bank.i.payload.addr.eq(local),
                bank.i.payload.rgb.eq(payload.rgb),
                bank.i.payload.z.eq(payload.z),
            ]
        m.d.comb += [
            owner[0].ready.eq(~slot & grant),
            owner[1].ready.eq(slot & grant),
        ]

        # Commands go to all banks at once, when all are idle.
        all_idle = Signal()
        m.d.comb += all_idle.eq(~self.busy)
        for bank in banks:
            m.d.comb += [
                bank.i_cmd.valid.eq(self.i_cmd.valid & all_idle),
                bank.i_cmd.payload.eq(self.i_cmd.payload),
            ]
        m.d.comb += [
            self.i_cmd.ready.eq(all_idle),
            self.busy.eq(_any(b.busy for b in banks)),
            self.idle.eq(~self.busy),
            self.draw_buf.eq(banks[0].draw_buf),
        ]

        # Read-back: route the linear address to its bank, select the data one clock later.
        rd_bank = Signal(range(n))
        rd_bank_q = Signal(range(n))
        m.d.comb += rd_bank.eq(self.rd_addr % n)
        m.d.sync += rd_bank_q.eq(rd_bank)
        for bank in banks:
            m.d.comb += [bank.rd_addr.eq(self.rd_addr // n), bank.rd_buf.eq(self.rd_buf)]
        m.d.comb += [
            self.rd_rgb.eq(Array(b.rd_rgb for b in banks)[rd_bank_q]),
            self.rd_z.eq(Array(b.rd_z for b in banks)[rd_bank_q]),
        ]
        return m


def _any(values):
    out = None
    for v in values:
        out = v if out is None else out | v
    return out
