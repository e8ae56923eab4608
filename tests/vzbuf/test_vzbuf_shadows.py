"""Shadow polygons and shadow map against the brute-force ray to the light; bad input."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Camera, Light, Scene
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.vzbuf.machine import render
from rasterhw.golden_model.vzbuf.render import render_frame
from rasterhw.golden_model.vzbuf.shadows import ray_shadow, screen_to_world

W = H = 512


@pytest.mark.parametrize("alg", [1, 2])
@pytest.mark.parametrize("name", ["c50", "sp8"])
def test_shadow_polygons_agree_with_rays(name, alg):
    sc = build_scene(name)
    f = render_frame(sc, W, H, alg=alg, shadows="polygons")
    vis = f.poly >= 0
    ray = ray_shadow(sc, W, H, f.depth, f.poly)
    assert ray[vis].mean() > 0.05          # there is shadow to agree on
    agree = (ray == f.shadowed)[vis].mean()
    assert agree >= 0.999, agree
    # darkened to Ia exactly where shadowed
    ia = 0.2
    assert np.allclose(f.inten[f.shadowed], ia)


def test_shadow_map_close_to_rays_and_polygons():
    sc = build_scene("sp8")
    fm = render_frame(sc, W, H, alg=2, shadows="map")
    fp = render_frame(sc, W, H, alg=2, shadows="polygons")
    vis = fm.poly >= 0
    assert np.array_equal(fm.poly, fp.poly)
    ray = ray_shadow(sc, W, H, fm.depth, fm.poly)
    agree = (ray == fm.shadowed)[vis].mean()
    assert 0.9 < agree < 1.0  # jagged outlines: close, not equal
    a1 = render_frame(sc, W, H, alg=1, shadows="map")
    assert np.array_equal(a1.shadowed, fm.shadowed)


def _box_scene(light=(0.0, -1.0, 0.0)) -> Scene:
    """A ground square and one floating cube straight under a light from above."""
    from rasterhw.golden_model.scenes import _CUBE_FACES, _CUBE_NORMALS

    corners = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)], float) * 2 - 1
    cube = corners[_CUBE_FACES] + np.array([0.0, 3.0, 0.0])
    cn = np.repeat(_CUBE_NORMALS[:, None, :], 4, axis=1)
    g = np.array([[[-6, 0, 6], [6, 0, 6], [6, 0, -6], [-6, 0, -6]]], float)
    gn = np.array([[[0, 1, 0]] * 4], float)
    pos = np.concatenate([g, cube])
    nrm = np.concatenate([gn, cn])
    cam = Camera(eye=(0.0, 14.0, 14.0), target=(0.0, 0.0, 0.0), near=1.0, far=100.0)
    return Scene(name="box", positions=pos, normals=nrm, colours=np.full(pos.shape, 0.8),
                 nverts=np.full(7, 4, np.int64), camera=cam, lights=(Light(direction=light),))


def test_ray_check_closed_form():
    """The brute force itself: light straight down, the cube's shadow is the 2x2 square."""
    sc = _box_scene()
    f = render_frame(sc, W, H, alg=2, shadows="none")
    ray = ray_shadow(sc, W, H, f.depth, f.poly)
    g = f.poly == 0
    rows, cols = np.nonzero(g)
    P = screen_to_world(sc, W, H, cols + 0.5, rows + 0.5, f.depth[rows, cols])
    under = (np.abs(P[:, 0]) < 1) & (np.abs(P[:, 2]) < 1)
    assert np.abs(P[:, 1]).max() < 1e-4  # the depth plane is refitted on snapped vertices
    assert under.sum() > 100
    assert np.array_equal(ray[rows, cols], under)
    fp = render_frame(sc, W, H, alg=2, shadows="polygons")
    assert (fp.shadowed[g] == under).mean() > 0.995


def test_bad_input():
    sc = build_scene("c50")
    nrm = sc.normals.copy()
    nrm[5] = 0.0
    with pytest.raises(RasterhwError, match="polygon 5 .* has no normal"):
        render(replace(sc, normals=nrm), W, H, arch="vz1")
    with pytest.raises(RasterhwError, match="eps must be"):
        render(sc, W, H, arch="vz2", shadows="map", eps=0.0)
    with pytest.raises(RasterhwError, match="eps must be"):
        render(sc, W, H, arch="vz2", shadows="map", eps=-1e-3)
    # light parallel to the screen: perpendicular to the view direction
    cam = sc.camera
    view = np.asarray(cam.target) - np.asarray(cam.eye)
    side = np.cross(view, [0.0, 1.0, 0.0])
    side = side / np.linalg.norm(side)
    par = tuple(np.cross(side, view / np.linalg.norm(view)) * -1 + 0 * side)
    with pytest.raises(RasterhwError, match="parallel to the screen"):
        render(replace(sc, lights=(Light(direction=par),)), W, H, arch="vz2", shadows="polygons")
    # no ground polygon under the shadow polygons
    with pytest.raises(RasterhwError, match="no ground polygon"):
        render(replace(sc, positions=sc.positions[1:], normals=sc.normals[1:], colours=sc.colours[1:],
                       nverts=sc.nverts[1:]), W, H, arch="vz1", shadows="polygons")
    with pytest.raises(RasterhwError, match="vz1 or vz2"):
        render(sc, W, H, arch="vz3")
    with pytest.raises(RasterhwError, match="shadows must be"):
        render(sc, W, H, arch="vz2", shadows="both")
    for msg in ("polygon 5", "eps", "parallel", "ground"):
        assert "\n" not in msg


def test_table1_light_shadow_polygons_agree_with_rays():
    """The render under vzbuf's table-1 light (low, from behind the eye) is still right."""
    from rasterhw.golden_model.vzbuf.workload import table1_light

    sc = table1_light(build_scene("c50"))
    f = render_frame(sc, W, H, alg=2, shadows="polygons")
    vis = f.poly >= 0
    ray = ray_shadow(sc, W, H, f.depth, f.poly)
    assert ray[vis].mean() > 0.05
    assert (ray == f.shadowed)[vis].mean() >= 0.999


def test_light_option():
    sc = build_scene("c50")
    a = render(sc, 64, 64, arch="vz2")
    b = render(sc, 64, 64, arch="vz2", light="table1")
    assert a.pixels_written == b.pixels_written
    assert not np.array_equal(a.rgb8, b.rgb8)   # the same polygons, lit from elsewhere
    with pytest.raises(RasterhwError, match="light must be scene or table1"):
        render(sc, 64, 64, arch="vz2", light="sun")
