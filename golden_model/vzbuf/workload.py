"""The light vzbuf renders the paper's scenes under, so that table 1's shadow workload is approached.

The shared scenes (``golden_model/scenes.py``: c50 ... c300, sp27, sp5, sp8) are used by every
machine and keep their own light. The paper gives no light direction: "光源光は平行光線とする"
(2.1: the light is parallel) and "セグメント数、面素数はスクリーン座標系における値であり、視線、
光線に依存する" (table 1 note 3: segments and pixels depend on the view and the light). Issue 27
item 4 asks for a light under which table 1's shadow-polygon counts and pixels per shadow
polygon are approached (within 25 %); this module is that choice, for vzbuf only (``--light
table1``; the report uses it for every table). It is a *workload* setting, chosen by sweeping the
light against table 1's two shadow rows (docs/vzbuf.md, "Shadow workload"); no timing parameter
depends on it, and the timing tables are then compared at a matched shadow workload. Tables 2
and 3 (no shadows), from which conclusions (a)-(e) are drawn, trace the same work under either
light (tested), so the choice cannot move a conclusion.

The light is set relative to the camera: ``elevation`` above the horizon, ``azimuth`` from the
camera's horizontal view direction toward its right (0 = the light travels the way the camera
looks, i.e. it comes from behind the eye). One setting per scene family, not per scene:

* cubes (``cN``): elevation 15 deg, azimuth 0 -- a low light from behind the viewer. Every cube
  scene is within 25 % over elevations 10-20 deg; the scenes' own light (elevation 54 deg, from
  behind the eye 34 deg to its right) gives 2.0-2.3 x the paper's pixels per shadow polygon.
* spheres (``spN``): elevation 30 deg, azimuth 45 deg. sp27 and sp8 are within 25 % for
  elevations 25-30 deg and azimuths 45-60 deg; below 25 deg a UV sphere's lit/unlit boundary
  zig-zags over more edges (sp8: 1.30 x the paper's shadow polygons). sp5 is not reached by any
  light or ground height tried (at most 0.57 x; docs/vzbuf.md says why).

The ground is left where the scenes put it (docs/vzbuf.md lists what raising and lowering it did).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

import numpy as np
from rasterhw.golden_model.scene import Light, Scene

__all__ = ["TABLE1_LIGHTS", "LightSetting", "table1_light"]


@dataclass(frozen=True)
class LightSetting:
    """A parallel light given relative to the camera (degrees)."""

    elevation_deg: float
    azimuth_deg: float

    def direction(self, scene: Scene) -> tuple[float, float, float]:
        """The light's travel direction in world space for ``scene``'s camera."""
        cam = scene.camera
        v = np.asarray(cam.target, float) - np.asarray(cam.eye, float)
        v[1] = 0.0
        v /= np.linalg.norm(v)
        right = np.array([-v[2], 0.0, v[0]])
        e, a = math.radians(self.elevation_deg), math.radians(self.azimuth_deg)
        d = math.cos(e) * (math.cos(a) * v + math.sin(a) * right) + np.array([0.0, -math.sin(e), 0.0])
        return tuple(float(c) for c in d)


#: one light per scene family of table 1 (see the module docstring and docs/vzbuf.md)
TABLE1_LIGHTS = {"cubes": LightSetting(15.0, 0.0), "spheres": LightSetting(30.0, 45.0)}


def _family(name: str) -> str | None:
    if re.fullmatch(r"c\d+", name):
        return "cubes"
    if re.fullmatch(r"sp\d+", name):
        return "spheres"
    return None


def table1_light(scene: Scene) -> Scene:
    """``scene`` under its family's table-1 light; any other scene (an OBJ mesh, ...) unchanged."""
    fam = _family(scene.name)
    if fam is None:
        return scene
    d = TABLE1_LIGHTS[fam].direction(scene)
    old = scene.lights[0]
    return replace(scene, lights=(Light(direction=d, colour=old.colour), *scene.lights[1:]))
