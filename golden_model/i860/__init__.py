"""An instruction-level timing model of the Intel i860 XR (80860), shared by the machines that
put one in front of their hardware (SNU's geometry pipeline, ZB/M's first-level processors).

A processor model, not a machine: it imports nothing from any machine package; the machines
write their programs with :class:`Program` and schedule them here. Every parameter is cited
in :data:`PARAMETERS` (and in ``docs/snu_geometry.md`` / ``docs/zbm.md``); none is taken from
either paper's tables.
"""

from rasterhw.golden_model.i860.model import (
    FP_REGISTERS,
    I860,
    NEWTON_STEPS,
    PARAMETERS,
    SCHEDULES,
    UNITS,
    ZERO_REGISTERS,
    Program,
    counts,
    schedule,
)

__all__ = ["FP_REGISTERS", "I860", "NEWTON_STEPS", "PARAMETERS", "SCHEDULES", "UNITS", "ZERO_REGISTERS",
           "Program", "counts", "schedule"]
