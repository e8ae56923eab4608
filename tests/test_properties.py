"""Property-based tests (hypothesis): whatever a user types or feeds in, the mesh loader, the
``--size`` and ``-p`` parsers and the screen-triangle validator give a result or one
:class:`RasterhwError` line -- never another exception. Example counts are kept modest
(CI time); ``HYPOTHESIS_PROFILE=soak`` runs many more."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from rasterhw.golden_model.errors import RasterhwError

settings.register_profile("ci", max_examples=60, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.register_profile("soak", max_examples=2000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def _one_line(e: RasterhwError) -> None:
    msg = str(e)
    assert msg and "\n" not in msg, msg


# ------------------------------------------------------------------ mesh loader
_num = st.one_of(st.integers(-5, 5).map(str), st.floats(allow_nan=True, allow_infinity=True).map(repr),
                 st.sampled_from(["nan", "inf", "-inf", "1e308", "1e400", "", "x", "0x10"]))
_idx = st.one_of(st.integers(-6, 8).map(str), st.sampled_from(["", "a", "1.5", "2/3", "1//2", "-0", "9" * 30]))
_obj_line = st.one_of(
    st.lists(_num, min_size=0, max_size=4).map(lambda v: "v " + " ".join(v)),
    st.lists(_idx, min_size=0, max_size=6).map(lambda v: "f " + " ".join(v)),
    st.sampled_from(["# caf\u00e9", "vn 0 0 1", "vt 0 0", "o x", "g", "mtllib none.mtl", "usemtl m", "s off", "\\"]),
    st.text(max_size=20),
)
_encodings = st.sampled_from(["utf-8", "utf-8-sig", "utf-16", "utf-16-le", "utf-16-be", "latin-1", "utf-32"])


@given(lines=st.lists(_obj_line, max_size=12), enc=_encodings)
def test_obj_text_loads_or_one_line_error(tmp_path_factory, lines, enc):
    from rasterhw.golden_model.meshio import load_mesh

    path = tmp_path_factory.mktemp("obj") / "m.obj"
    path.write_bytes("\n".join(lines).encode(enc, errors="replace"))
    try:
        sc = load_mesh(path)
    except RasterhwError as e:
        _one_line(e)
        return
    assert np.all(np.isfinite(sc.positions)) and sc.positions.shape[1:] == (3, 3)


@given(raw=st.binary(max_size=400), ext=st.sampled_from([".obj", ".ply"]))
def test_arbitrary_bytes_load_or_one_line_error(tmp_path_factory, raw, ext):
    from rasterhw.golden_model.meshio import load_mesh

    path = tmp_path_factory.mktemp("raw") / f"m{ext}"
    path.write_bytes(raw)
    try:
        load_mesh(path)
    except RasterhwError as e:
        _one_line(e)


_ply_header = st.builds(
    lambda fmt, nv, nf, body: (f"ply\nformat {fmt} 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
                               f"property float z\nelement face {nf}\nproperty list uchar int vertex_indices\n"
                               "end_header\n").encode() + body,
    st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian"]),
    st.integers(-1, 10), st.integers(-1, 5), st.binary(max_size=200))


@given(raw=_ply_header)
def test_ply_headers_load_or_one_line_error(tmp_path_factory, raw):
    from rasterhw.golden_model.meshio import load_mesh

    path = tmp_path_factory.mktemp("ply") / "m.ply"
    path.write_bytes(raw)
    try:
        load_mesh(path)
    except RasterhwError as e:
        _one_line(e)


# ------------------------------------------------------------------ --size
@given(text=st.one_of(st.text(max_size=24), st.builds(lambda a, b, s: f"{a}{s}{b}", st.integers(-10, 20000),
                                                       st.integers(-10, 20000), st.sampled_from(["x", "X", "*", " x ", "_"]))))
def test_size_parser_result_or_one_line_error(text):
    from rasterhw.sim.cli.main import parse_size

    try:
        w, h = parse_size(text)
    except RasterhwError as e:
        _one_line(e)
        return
    assert 1 <= w <= 16384 and 1 <= h <= 16384
    assert parse_size(f"{w}x{h}") == (w, h)


# ------------------------------------------------------------------ -p NAME=VALUE
def _factories():
    from rasterhw.sim import registry

    return sorted(registry.blocks())


_value = st.one_of(st.text(max_size=12), st.integers().map(str), st.sampled_from(["true", "False", "0x10", "1e3", "-1"]))


@pytest.mark.parametrize("block", _factories())
@given(data=st.data())
def test_param_parser_result_or_one_line_error(block, data):
    import inspect

    from rasterhw.sim import registry
    from rasterhw.sim.engines.verilog import parse_params

    factory = registry.load(registry.blocks()[block])
    names = list(inspect.signature(factory).parameters) + ["nonsense", ""]
    pairs = data.draw(st.lists(st.one_of(
        st.builds(lambda k, v: f"{k}={v}", st.sampled_from(names), _value), st.text(max_size=10)), max_size=4))
    try:
        kw = parse_params(tuple(pairs), factory)
    except RasterhwError as e:
        _one_line(e)
        return
    sig = inspect.signature(factory).parameters
    for k, v in kw.items():
        d = sig[k].default
        if isinstance(d, bool):
            assert isinstance(v, bool)
        elif isinstance(d, int):
            assert isinstance(v, int) and not isinstance(v, bool)


# ------------------------------------------------------------------ screen triangles
_f = st.floats(allow_nan=True, allow_infinity=True, width=64)


@given(t=st.integers(0, 6), w=st.one_of(st.integers(-2, 40), st.just(True), st.just(2.5)),
       h=st.one_of(st.integers(-2, 40), st.just(10**9)), data=st.data())
def test_screen_triangles_validate_or_one_line_error(t, w, h, data):
    from rasterhw.golden_model.reference import rasterise
    from rasterhw.golden_model.screen import ScreenTriangles

    def arr(shape, elems):
        return np.array(data.draw(st.lists(elems, min_size=int(np.prod(shape)), max_size=int(np.prod(shape)))),
                        dtype=np.float64).reshape(shape)

    bad_shape = data.draw(st.booleans()) and data.draw(st.booleans())
    xy = arr((t, 3, 2), st.one_of(st.floats(-50, 90), _f)) if not bad_shape else np.zeros((t, 2))
    z = arr((t, 3), st.one_of(st.floats(0, 1), _f))
    col = arr((t, 3, 3), st.floats(0, 1))
    tris = ScreenTriangles(width=w, height=h, xy=xy, z=z, zq=np.zeros((t, 3), np.int64), colour=col,
                           poly_id=np.arange(t))
    try:
        tris.validate()
        frame = rasterise(tris)
    except RasterhwError as e:
        _one_line(e)
        return
    assert frame.colour.shape == (h, w, 3)
