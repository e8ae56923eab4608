"""SNU pixel-bus formats: the one place the machine's widths and timing constants live.

The HDL (``hdl/snu/``), the golden models (``golden_model/snu/``) and the benches take their
defaults from here (paper, sec. 4.4-4.5: 1280x1024 frame, RGB 24 bits, Z 24 bits far = 0,
5:1 interleaved banks, 400 ns memory cycle on an 80 ns bus slot, two pipelines).
"""

from __future__ import annotations

__all__ = ["CLOCK_HZ", "FRAME_HEIGHT", "FRAME_WIDTH", "MEM_CYCLE", "N_BANKS", "N_PIPES", "RGB_BITS",
           "Z_BITS"]

FRAME_WIDTH = 1280   #: pixels per line
FRAME_HEIGHT = 1024  #: lines
RGB_BITS = 24        #: r << 16 | g << 8 | b, 8 bits each
Z_BITS = 24          #: stored depth; far = 0, larger is nearer
N_BANKS = 5          #: 5:1 interleave, bank = addr % 5
MEM_CYCLE = 5        #: clocks per bank memory cycle: 400 ns / 80 ns
N_PIPES = 2          #: geometry pipelines sharing the bus by fixed slots
CLOCK_HZ = 12.5e6    #: one 80 ns bus slot per clock
