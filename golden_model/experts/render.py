"""The EXPERTS golden renderer as ``rasterhw render --arch experts`` runs it."""

from __future__ import annotations

from rasterhw.golden_model.arch import Rendered
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.experts.formats import MAX_SIDE, Z_BITS, Formats
from rasterhw.golden_model.experts.model import render_frame, stage_totals
from rasterhw.golden_model.experts.parallel import run_parallel
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scene import Scene

__all__ = ["render"]


def render(scene: Scene, width: int, height: int, *, arch: str = "experts", aj: str | None = "c",
           model: str | None = "bit", sn: int | None = 8, pn: int | None = 8,
           intensity_bits: int | None = 7, shadows: str | None = "none") -> Rendered:
    """One frame through the SLP/PXP golden model; stats carry the 8 x 8 (or Sn x Pn) timing.

    ``pixels_written`` counts DSLB writes (every pixel of every line, background included).
    """
    aj = "c" if aj is None else aj
    model = "bit" if model is None else model
    sn = 8 if sn is None else sn
    pn = 8 if pn is None else pn
    for name, v, hi, what in (("sn", sn, height, "lines"), ("pn", pn, width, "pixels per line")):
        if isinstance(v, bool) or not isinstance(v, int) or not 1 <= v <= hi:
            raise RasterhwError(f"experts: --{name} must be an integer from 1 to the frame's {hi} {what}, not {v!r}")
    if width > MAX_SIDE or height > MAX_SIDE:
        raise RasterhwError(f"experts: frame {width}x{height} is larger than the Q10.6 vertex coordinates allow: "
                            f"at most {MAX_SIDE} px a side (a vertex on the right or bottom edge sits at x = width, "
                            "and Q10.6 holds at most 1023.98)")
    shadows = "none" if shadows is None else shadows
    if shadows not in ("none", "polygons"):
        raise RasterhwError(f"experts: shadows must be none or polygons, not {shadows!r}")
    tris = run_geometry(scene, width, height, z_bits=Z_BITS)
    sf = None
    if shadows == "polygons":
        from rasterhw.golden_model.experts.shadow import shadow_faces
        sf = shadow_faces(scene, width, height, z_bits=Z_BITS)
    f = render_frame(tris, model=model, aj=aj, fmt=Formats(7 if intensity_bits is None else intensity_bits),
                     shadows=sf)
    par = run_parallel(f, sn, pn, band_method="pl", range_method="ii")
    ops = stage_totals(f, sn=sn, pn=pn)
    return Rendered(f.rgb8, tris, width * height,
                    {"model": model, "aj": aj, "sn": sn, "pn": pn, "aj_pixels": f.aj_pixels,
                     "operations": int(sum(ops.values())), "frame_op_times": round(par.frame_time, 1),
                     "pxp_imbalance": round(par.imbalance(), 4), "crossings": f.stats["crossings"],
                     "pixels_covered": int(f.covered.sum()),
                     "shadows": shadows, **({"shadowed_pixels": f.stats["shadowed_pixels"]} if sf else {})})
