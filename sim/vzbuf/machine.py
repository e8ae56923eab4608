"""Registry entry of the vector Z-buffer machine (FACOM VP100/VP200, seed 001)."""

from __future__ import annotations

from rasterhw.sim.registry import Arch, Machine, Option

_OPTIONS = (
    Option("shadows", "Shadows: none, Crow's shadow polygons, or ray casting with a shadow map.",
           default="none", choices=("none", "polygons", "map")),
    Option("eps", "Shadow-map epsilon in light depth units (scene depth mapped to 0..1); > 0.",
           default=5e-3, type=float),
)

MACHINE = Machine(
    name="vzbuf",
    title="Vector Z-buffer on the FACOM VP100/VP200 (Kitai, Niimi, Tomita, Hagiwara)",
    seed="001_96e5154526ae973d.txt",
    archs=(
        Arch("vz1", "Vector Z-buffer, algorithm 1: one-line Z-buffer, x-list, span-length vectors.",
             "rasterhw.golden_model.vzbuf.machine:render", _OPTIONS, bytes_per_pixel=170),  # measured ~130
        Arch("vz2", "Vector Z-buffer, algorithm 2: split segments, full-frame Z-buffer, s-list "
             "(one segment per line), line-count vectors.",
             "rasterhw.golden_model.vzbuf.machine:render", _OPTIONS, bytes_per_pixel=170),
    ),
    report="rasterhw.sim.vzbuf.report:rows",
    bench="rasterhw.sim.vzbuf.bench:bench",
    status="golden model: algorithms 1 and 2, Gouraud, shadow polygons, shadow map (NumPy), with the "
           "vector-operation trace priced on the scalar unit, VP100 and VP200; tables 1-7 side by side",
)
