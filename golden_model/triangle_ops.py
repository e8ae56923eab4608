"""Operation counts of the golden geometry pipeline on one triangle (the SNU paper's table 1
assumptions): :func:`ops_per_triangle` runs :func:`rasterhw.golden_model.pipeline.run_geometry`
on one lit, unclipped, front-facing triangle and returns what its :class:`OpCounter` tallied."""

from __future__ import annotations

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.opcount import zero_counts
from rasterhw.golden_model.pipeline import STAGES, run_geometry
from rasterhw.golden_model.scene import Camera, Light, Material, Scene

__all__ = ["default_triangle_scene", "ops_per_triangle"]


def default_triangle_scene():
    """A single lit, unclipped, front-facing triangle with the full Phong model on."""
    pos = np.array([[[-1.0, -0.8, 0.0], [1.0, -0.6, -0.3], [0.1, 0.9, 0.2]]])
    nrm = np.array([[[-0.2, -0.1, 1.0], [0.3, -0.1, 1.0], [0.0, 0.3, 1.0]]])
    col = np.array([[[0.8, 0.3, 0.2], [0.3, 0.7, 0.2], [0.2, 0.3, 0.8]]])
    return Scene(
        name="one-triangle",
        positions=pos,
        normals=nrm,
        colours=col,
        nverts=np.array([3]),
        camera=Camera(eye=(0.0, 0.0, 5.0), target=(0.0, 0.0, 0.0), near=0.5, far=50.0),
        lights=(Light(direction=(-0.3, -0.4, -1.0), colour=(1.0, 1.0, 1.0)),),
        ambient=(0.2, 0.2, 0.2),
        material=Material(ka=1.0, kd=0.6, ks=0.3, shininess=16),
    )


def ops_per_triangle(
    scene=None, *, width: int = 1280, height: int = 1024
) -> dict[str, dict[str, int]]:
    """Run the pipeline on one triangle and return its per-stage operation counts.

    The default scene is one lit, front-facing triangle fully inside the view volume,
    one directional light, specular on (``ks > 0``), drawn at the SNU system's
    1280 x 1024 with a 24-bit Z flipped so far = 0 -- the paper's assumptions for
    table 1. A given ``scene`` must be one triangle that is drawn without being cut by
    a clip plane. Returns stage -> {category: count, "total": n} in pipeline order
    plus a ``"total"`` row.
    """
    scene = default_triangle_scene() if scene is None else scene
    if scene.n_polygons != 1 or int(scene.nverts[0]) != 3:
        raise RasterhwError(
            f"ops_per_triangle needs a scene of one triangle, got {scene.n_polygons} polygons "
            f"with {scene.nverts.tolist()} corners"
        )
    tris = run_geometry(scene, width, height, z_bits=24, z_far_is_zero=True)
    if (
        tris.stats["polygons_drawn"] != 1
        or tris.stats["polygons_cut"] != 0
        or tris.n_triangles != 1
    ):
        raise RasterhwError(
            f"ops_per_triangle needs a front-facing triangle inside the view volume; stats: {tris.stats}"
        )
    out = {s: dict(tris.ops[s]) for s in STAGES}
    total = zero_counts() | {"total": 0}
    for row in out.values():
        for k in total:
            total[k] += row[k]
    out["total"] = total
    return out
