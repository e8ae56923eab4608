"""ZB/M golden model (Matsushita scan-line Z-buffer merger, seed 003), one module per hardware
stage, named as the HDL blocks (``hdl/zbm/``) and the docs (``docs/zbm.md``):

``formats``     the one place the widths live (word layouts shared with the HDL)
``edgepair``    level-1 processors: triangles -> edge pairs
``seggen``      segment generator: edge pairs -> segments per scan line
``initial``     initial processor: segment -> this chip's packet
``chip``        segment loop of 8 pixel processors into double-Z pixel memories
``unit``        a unit: segment generator + interleaved chips
``merger``      nearest 2 of 4 samples on the merge bus
``mapping``     texture / illumination lookups after the merge
``composite``   alpha-compositing of the final 2 samples
``render``      the whole machine, bit-accurate (``render_zbm``) and float (``render_zbm_float``)
``cycles``      cycle models (paper rules, the HDL's exact schedule, the formula)
``words``       packing of golden values into the HDL's port words
"""

from rasterhw.golden_model.zbm.chip import chip_scanline
from rasterhw.golden_model.zbm.composite import composite
from rasterhw.golden_model.zbm.doublez import DoubleZ
from rasterhw.golden_model.zbm.edgepair import EdgePairs, edge_pairs
from rasterhw.golden_model.zbm.formats import Z_SCALE
from rasterhw.golden_model.zbm.initial import initial_processor
from rasterhw.golden_model.zbm.mapping import default_maps, map_samples
from rasterhw.golden_model.zbm.merger import merge, merge_chain
from rasterhw.golden_model.zbm.render import (
    ZbmResult,
    chain_frame,
    render_scene,
    render_zbm,
    render_zbm_float,
)
from rasterhw.golden_model.zbm.seggen import Segments, max_active_edge_pairs, segment_generator
from rasterhw.golden_model.zbm.unit import unit_scanline

__all__ = [
    "Z_SCALE", "DoubleZ", "EdgePairs", "Segments", "ZbmResult", "chip_scanline", "composite",
    "default_maps", "edge_pairs", "initial_processor", "map_samples", "max_active_edge_pairs", "merge",
    "chain_frame", "merge_chain", "render_scene", "render_zbm", "render_zbm_float", "segment_generator", "unit_scanline",
]
