"""The SNU machine's golden renderer: geometry -> fixed-point Gouraud scan converter ->
pixel-bus frame buffer model (far = 0, 24-bit Z), as ``rasterhw render --arch snu`` runs it."""

from __future__ import annotations

from rasterhw.golden_model.arch import Rendered
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.snu.formats import Z_BITS
from rasterhw.golden_model.snu.gouraud import scan_convert
from rasterhw.golden_model.snu.pixelbus import pixelbus_frame, rgb_image

__all__ = ["render"]


def render(scene: Scene, width: int, height: int, *, arch: str = "snu") -> Rendered:
    """One frame through the SNU golden models; ``pixels_written`` counts bus writes."""
    tris = run_geometry(scene, width, height, z_bits=Z_BITS, z_far_is_zero=True)
    stream = scan_convert(tris)
    rgb, z = pixelbus_frame(stream)
    return Rendered(rgb_image(rgb), tris, len(stream),
                    {"pixel_writes": len(stream), "pixels_covered": int((z > 0).sum())})
