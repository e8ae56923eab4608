"""Registry entry of the vector Z-buffer machine (FACOM VP100/VP200, seed 001)."""

from __future__ import annotations

from rasterhw.sim.registry import Arch, Machine, Option

_OPTIONS = (
    Option("shadows", "Shadows: none, Crow's shadow polygons, or ray casting with a shadow map.",
           default="none", choices=("none", "polygons", "map")),
    Option("eps", "Shadow-map epsilon in light depth units (scene depth mapped to 0..1); > 0.",
           default=5e-3, type=float),
    Option("light", "Light: the scene's own, or vzbuf's table-1 light (chosen so that the paper's scenes approach "
           "table 1's shadow workload; docs/vzbuf.md).", default="scene", choices=("scene", "table1")),
)

#: why vz1/vz2's RGB differs from the float reference (docs/vzbuf.md, "Output")
_COLOUR = ("Colour by design: the paper's pixel is RGBI 3/3/3/7 bits (section 3.1 d): the face's RGB to 3 bits "
           "each, the Gouraud intensity to 7; coverage and the visible polygon equal the reference's.")

MACHINE = Machine(
    name="vzbuf",
    title="Vector Z-buffer on the FACOM VP100/VP200 (Kitai, Niimi, Tomita, Hagiwara)",
    seed="001_96e5154526ae973d.txt",
    archs=(
        Arch("vz1", "Vector Z-buffer, algorithm 1: one-line Z-buffer, x-list, span-length vectors.",
             "rasterhw.golden_model.vzbuf.machine:render", _OPTIONS, bytes_per_pixel=170, colour_note=_COLOUR),  # measured ~130
        Arch("vz2", "Vector Z-buffer, algorithm 2: split segments, full-frame Z-buffer, s-list "
             "(one segment per line), line-count vectors.",
             "rasterhw.golden_model.vzbuf.machine:render", _OPTIONS, bytes_per_pixel=170, colour_note=_COLOUR),
    ),
    report="rasterhw.sim.vzbuf.report:rows",
    headline=("table 3: c300: total", "table 3: c300: vectorisation gain", "table 2: c300: vectorisation gain",
              "table 3: sp8: total", "table 1: c300: processed polygons"),
    no_hdl="The paper's machine is a general-purpose vector computer (FACOM VP100/VP200) running vectorised "
           "FORTRAN, not a block of logic: its model is the algorithms' vector-operation trace priced on "
           "the scalar unit, VP100 and VP200 (docs/vzbuf.md).",
    frame_cost="rasterhw.sim.vzbuf.frame:frame_cost",
    bench="rasterhw.sim.vzbuf.bench:bench",
    status="golden model: algorithms 1 and 2, Gouraud, shadow polygons, shadow map (NumPy), with the "
           "vector-operation trace priced on the scalar unit, VP100 and VP200; tables 1-7 side by side",
)
