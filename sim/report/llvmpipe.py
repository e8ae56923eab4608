"""Mesa llvmpipe on the same screen triangles as the reference rasteriser (``rasterhw bench``).

A yardstick, not a model: how fast a compiled software rasteriser draws what
:func:`rasterhw.golden_model.reference.rasterise` draws. Optional: it needs ``moderngl``
(``pip install 'rasterhw[bench]'``) and an EGL library (Mesa's ``libEGL_mesa``); when either
is missing :func:`llvmpipe_bench` says why instead of timing.

What is drawn: the vertices snapped exactly as the reference snaps them
(:func:`rasterhw.golden_model.screen.snap`, 1/256 px, the same grid as llvmpipe's own 8
sub-pixel bits), the same submission order, depth ``z`` in a 32-bit float depth buffer with
the test ``GL_LESS`` (strict: on a tie the triangle drawn first keeps the pixel), Gouraud
colour into an RGBA8 target and the triangle index (flat) into an R32I target, on a
standalone (headless) EGL context with a ``width x height`` framebuffer.

What is timed, per run: vertex upload, clear, draw, ``glFinish`` and the read-back of both
targets to host memory (the reference returns its whole frame in host memory too). Context
creation, shader compilation and buffer allocation are done once, before the timed runs.
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np
from rasterhw.golden_model.screen import SUBPIXEL_BITS, ScreenTriangles, snap

_VS = """
#version 330
uniform vec2 size;
in vec2 in_xy;      // window position in pixels, y down (row 0 on top)
in float in_z;      // depth in [0, 1], 0 = near
in vec3 in_col;
in int in_id;
out vec3 v_col;
flat out int v_id;
void main() {
    // x_ndc * size/2 + size/2 = x: the viewport maps back to the same pixels. Our row 0 is
    // the framebuffer's row 0 (the first row read back), so y is not flipped. Whether
    // llvmpipe's tie rule is then our top-left rule is measured, not assumed
    // (tests/test_llvmpipe.py, edges through pixel centres).
    gl_Position = vec4(in_xy / size * 2.0 - 1.0, in_z * 2.0 - 1.0, 1.0);
    v_col = in_col;
    v_id = in_id;
}
"""
_FS = """
#version 330
in vec3 v_col;
flat in int v_id;
layout(location = 0) out vec4 f_col;
layout(location = 1) out int f_id;
void main() { f_col = vec4(v_col, 1.0); f_id = v_id + 1; }  // 0 = empty (the clear value)
"""


class Unavailable(Exception):
    """moderngl or an EGL context is not available here (the message says which)."""


class Llvmpipe:
    """A standalone EGL context with llvmpipe and a ``width x height`` framebuffer."""

    def __init__(self, width: int, height: int):
        try:
            import moderngl
        except ImportError as e:
            raise Unavailable(f"moderngl not installed ({e}); pip install 'rasterhw[bench]'") from None
        try:
            ctx = moderngl.create_standalone_context(backend="egl", require=330)
        except Exception as e:  # no libEGL, no EGL device, no GL 3.3
            raise Unavailable(f"no EGL context: {str(e).splitlines()[0] if str(e) else type(e).__name__}") from None
        self.renderer = str(ctx.info.get("GL_RENDERER", "?"))
        self.version = str(ctx.info.get("GL_VERSION", "?"))
        self.ctx = ctx
        self.width, self.height = int(width), int(height)
        self.prog = ctx.program(vertex_shader=_VS, fragment_shader=_FS)
        self.prog["size"].value = (float(width), float(height))
        self.col_rb = ctx.renderbuffer((width, height), components=4, dtype="f1")
        self.id_rb = ctx.renderbuffer((width, height), components=1, dtype="i4")
        self.depth_rb = ctx.depth_renderbuffer((width, height))  # GL_DEPTH_COMPONENT24 in moderngl
        self.fbo = ctx.framebuffer(color_attachments=[self.col_rb, self.id_rb], depth_attachment=self.depth_rb)
        self._vbo = None
        self._vao = None
        self._n = 0

    def close(self) -> None:
        self.ctx.release()

    def load(self, tris: ScreenTriangles) -> np.ndarray:
        """The vertex array for ``tris`` (interleaved float32 x, y, z, r, g, b and int32 id).

        Snapped positions are multiples of 1/256 px below 2**16 px, so float32 holds them
        exactly."""
        t = tris.n_triangles
        rec = np.empty((t, 3), dtype=[("xy", "f4", 2), ("z", "f4"), ("col", "f4", 3), ("id", "i4")])
        rec["xy"] = snap(tris.xy) / (1 << SUBPIXEL_BITS)
        rec["z"] = tris.z
        rec["col"] = tris.colour
        rec["id"] = np.arange(t, dtype=np.int32)[:, None]
        return rec.reshape(-1)

    def draw(self, verts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Upload, draw and read back: ``(rgba8 (H, W, 4), tri_id (H, W) int32, -1 = empty)``.
        Row 0 is the top row (our convention)."""
        import moderngl

        ctx = self.ctx
        data = verts.tobytes()
        if self._vbo is None or self._vbo.size < len(data):
            if self._vbo is not None:
                self._vao.release()
                self._vbo.release()
            self._vbo = ctx.buffer(reserve=max(len(data), 1))
            self._vao = ctx.vertex_array(self.prog, [(self._vbo, "2f 1f 3f 1i", "in_xy", "in_z", "in_col", "in_id")])
        self._vbo.write(data)
        self.fbo.use()
        ctx.viewport = (0, 0, self.width, self.height)
        ctx.enable(moderngl.DEPTH_TEST)
        ctx.disable(moderngl.CULL_FACE)
        ctx.depth_func = "<"
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)  # every target to 0: id target 0 = empty
        self._vao.render(moderngl.TRIANGLES, vertices=verts.size)
        ctx.finish()
        rgba = np.frombuffer(self.fbo.read(components=4, attachment=0, dtype="f1"), np.uint8)
        ids = np.frombuffer(self.fbo.read(components=1, attachment=1, dtype="i4"), np.int32)
        return rgba.reshape(self.height, self.width, 4), ids.reshape(self.height, self.width) - 1


def compare(tris: ScreenTriangles, repeat: int, ours) -> dict:
    """Time llvmpipe and ``ours`` (a callable rendering ``tris``, returning a reference
    :class:`~rasterhw.golden_model.reference.Frame` or a
    :class:`~rasterhw.golden_model.reference.Target` holding ``tri_id``) side by side: ``repeat`` rounds, each
    one run of ours then one draw of llvmpipe, so both see the same machine load; medians.

    Returns ``{"ours_s", "llvmpipe_s", "ratio", "repeat", "ours_min_s", "llvmpipe_min_s",
    "ours_cpu_s", "llvmpipe_cpu_s",
    "renderer", "threads", "coverage_diff", "winner_diff"}``: wall-clock medians, and
    medians of the CPU time of the whole process (all llvmpipe's threads counted; a fairer
    comparison on a loaded machine, where a single-threaded NumPy run waits for a core); ``coverage_diff`` counts pixels covered by one
    renderer and not the other, ``winner_diff`` pixels whose visible triangle differs (depth
    is interpolated in float32 there, so near-ties may go either way; reported, not
    asserted). Raises :class:`Unavailable` when there is no moderngl or EGL."""
    gl = Llvmpipe(tris.width, tris.height)
    try:
        verts = gl.load(tris)
        gl.draw(verts)  # warm-up: the first draw compiles llvmpipe's shader variants
        frame = ours()
        t_ours, t_gl, c_ours, c_gl = [], [], [], []
        ids = None
        for _ in range(repeat):
            c0, t0 = time.process_time(), time.perf_counter()
            frame = ours()
            c1, t1 = time.process_time(), time.perf_counter()
            _, ids = gl.draw(verts)
            c2, t2 = time.process_time(), time.perf_counter()
            t_ours.append(t1 - t0)
            t_gl.append(t2 - t1)
            c_ours.append(c1 - c0)
            c_gl.append(c2 - c1)
        if ids is None:
            _, ids = gl.draw(verts)
        mine = np.asarray(frame.tri_id)
        m_ours, m_gl = statistics.median(t_ours), statistics.median(t_gl)
        return {"ours_s": m_ours, "llvmpipe_s": m_gl, "ratio": m_ours / m_gl, "repeat": repeat,
                "ours_min_s": min(t_ours), "llvmpipe_min_s": min(t_gl),
                "ours_cpu_s": statistics.median(c_ours), "llvmpipe_cpu_s": statistics.median(c_gl),
                "renderer": gl.renderer, "threads": threads(),
                "coverage_diff": int(np.count_nonzero((mine >= 0) != (ids >= 0))),
                "winner_diff": int(np.count_nonzero(mine != ids))}
    finally:
        gl.close()


def threads() -> str:
    """llvmpipe's rasteriser threads: ``LP_NUM_THREADS`` if set, else its default (one per CPU)."""
    return os.environ.get("LP_NUM_THREADS", f"{os.cpu_count()} (one per CPU, Mesa's default)")
