"""The registry's renderer for archs ``vz1`` and ``vz2``."""

from __future__ import annotations

from rasterhw.golden_model.arch import Rendered
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.vzbuf.render import DEFAULT_EPS, render_frame
from rasterhw.golden_model.vzbuf.workload import table1_light

__all__ = ["render"]


def render(scene: Scene, width: int, height: int, *, arch: str, shadows: str = "none",
           eps: float = DEFAULT_EPS, light: str = "scene") -> Rendered:
    """``rasterhw render SCENE --arch vz1|vz2 [--shadows none|polygons|map] [--eps E] [--light scene|table1]``.

    ``--light table1`` renders the paper's scenes under vzbuf's table-1 light (``workload.py``).
    """
    algs = {"vz1": 1, "vz2": 2}
    if arch not in algs:
        raise RasterhwError(f"vzbuf: arch must be vz1 or vz2, not {arch!r}")
    if light not in ("scene", "table1"):
        raise RasterhwError(f"vzbuf: light must be scene or table1, not {light!r}")
    if light == "table1":
        scene = table1_light(scene)
    f = render_frame(scene, width, height, alg=algs[arch], shadows=shadows, eps=eps)
    c = f.stats["counters"]
    stats = {"stages_s": f.stages, "segments": f.stats["segments"], "passes": c["passes"],
             "ztests": c["ztests"], "mean_vector_length": c["mean_vector_length"],
             "pixels_real": f.stats["pixels_real"], "pixels_shadow": f.stats["pixels_shadow"],
             "shadowed_pixels": int(f.shadowed.sum()), "pixels_covered": int((f.poly >= 0).sum())}
    return Rendered(rgb8=f.rgb8, tris=f.sp.tris, pixels_written=int(c["written"]), stats=stats)
