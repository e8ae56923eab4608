"""``rasterhw render SCENE --arch sparse --matrix PxQ``: the matrix-pipeline generator's golden renderer."""

from __future__ import annotations

from rasterhw.golden_model.arch import Rendered
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.sparse.formats import parse_matrix, sparse_geometry
from rasterhw.golden_model.sparse.search import sparse_render

__all__ = ["render"]


def render(scene, width: int, height: int, *, arch: str = "sparse", matrix: str = "4x4",
           z_bits: int = 24) -> Rendered:
    """Geometry pipeline, then the ``p x q`` matrix of video processors (float layer, whose image
    equals the reference rasteriser's). ``scene`` is a :class:`Scene` or a built-in scene name."""
    if arch != "sparse":
        raise RasterhwError(f"sparse renderer: unknown arch {arch!r}")
    p, q = parse_matrix(matrix)
    sparse_geometry(width, height, p, q)  # fail before the geometry stage
    if isinstance(scene, str):
        from rasterhw.golden_model.scenes import build_scene

        scene = build_scene(scene)
    if not isinstance(scene, Scene):
        raise RasterhwError(f"sparse renderer needs a Scene, got {type(scene).__name__}")
    tris = run_geometry(scene, width, height, z_bits=z_bits)
    f = sparse_render(tris, (p, q))
    return Rendered(rgb8=f.to_rgb8(), tris=tris, pixels_written=f.pixels_written,
                    stats={"matrix": f"{p}x{q}", "n": f.n, "fragments": f.fragments,
                           "pixels_covered": int((f.tri_id >= 0).sum()),
                           "windows_per_level": [int(v) for v in f.windows],
                           "coverage_tests_per_level": [int(v) for v in f.tests],
                           "coverage_tests": int(f.tests.sum()),
                           "max_tests_per_processor": int(f.tests_per_proc.sum(axis=1).max())})
