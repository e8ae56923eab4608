"""The word format of the SNU frame bench (``frame_adapter.FrameAdapter``): the bits of a producer
gap and the words of the schedule port ``o_sched``, in order. Its own module, without Amaranth, so
the frame's stimulus and golden words (``testbench.py``, ``scene.py``) are made without importing
the adapter's HDL."""

from __future__ import annotations

__all__ = ["GAP_BITS", "SCHEDULE"]

GAP_BITS = 16
#: the words of ``o_sched``, in order
SCHEDULE = ("t_clear", "t_start", "t_pixels_done", "t_swap", "cycles")
