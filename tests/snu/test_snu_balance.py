"""SNU table 1 / stage balance (golden_model/snu/balance.py) and PHIGS traversal
(golden_model/snu/traversal.py)."""

from __future__ import annotations

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.scene import Scene
from rasterhw.golden_model.snu import balance as b
from rasterhw.golden_model.snu import traversal as tv

# ------------------------------------------------------------------ table 1 constants


def test_paper_table_is_self_consistent():
    t = b.PAPER_TABLE1
    assert sum(r["ops"] for r in t.values()) == b.PAPER_TOTAL_OPS == 270
    assert sum(r["clocks"] for r in t.values()) == b.PAPER_TOTAL_CLOCKS == 309
    for s, r in t.items():  # the percent column is clocks / 309, to one decimal
        assert round(100 * r["clocks"] / 309, 1) == r["percent"], s


def test_text_op_mixes_against_the_table():
    per_tri = b.per_triangle(b.PAPER_TEXT_COUNTS)
    agree = [s for s in b.STAGES if per_tri[s]["total"] == b.PAPER_TABLE1[s]["ops"]]
    # The text matches the table except lighting (text 26/vertex = 78, table 72) and
    # clipping (text 6 compares/vertex = 18, table 24); the two differences cancel in the sum.
    assert set(b.STAGES) - set(agree) == {"light", "clip"}
    assert per_tri["light"]["total"] == 78 and per_tri["clip"]["total"] == 18
    assert sum(per_tri[s]["total"] for s in b.STAGES) == 270


# ------------------------------------------------------------------ balance and Mflops


def test_balance_on_paper_clocks():
    bal = b.balance({s: b.PAPER_TABLE1[s]["clocks"] for s in b.STAGES}, clock_hz=40e6)
    assert bal["groups"] == {"P1 transform": 99, "P2 normalise+light": 141, "P3 clip+project+map": 69}
    assert bal["bottleneck"] == "P2 normalise+light"
    assert bal["polys_per_s_pipeline"] == pytest.approx(40e6 / 141)
    assert bal["polys_per_s_system"] == pytest.approx(2 * 40e6 / 141)
    assert bal["polys_per_s_one_processor"] == pytest.approx(40e6 / 309)


def test_mflops_on_paper_ops():
    mf = b.mflops({s: b.PAPER_TABLE1[s]["ops"] for s in b.STAGES})
    assert [round(mf[s], 3) for s in b.STAGES] == [7.2, 4.5, 3.0, 7.2, 2.4, 1.2, 1.5]
    # the paper's text says 1.8 for clipping: 18 compares, not the table's 24
    assert b.mflops(b.per_triangle(b.PAPER_TEXT_COUNTS))["clip"] == pytest.approx(b.PAPER_MFLOPS["clip"])


def test_table1_rows():
    from rasterhw.golden_model.snu import i860, recipe
    from rasterhw.golden_model.triangle_ops import ops_per_triangle as full_ops

    rows = b.table1_rows(recipe.ops_per_triangle(), full_ops(), i860.table1_model())
    keys = ("system", "figure", "quantity", "paper", "formula", "measured", "unit", "source")
    assert all(tuple(r) == keys for r in rows)
    by_q = {r["quantity"]: r for r in rows}
    assert by_q["total operations per triangle, paper's recipe"]["measured"] == 270
    assert by_q["light: operations per triangle, paper's recipe (formula = the text)"]["measured"] == 78
    assert by_q["light: operations per triangle, paper's recipe (formula = the text)"]["paper"] == 72
    assert by_q["backface_cull: operations per triangle, our full pipeline (not in the paper)"]["measured"] == 15
    clocks = [r for r in rows if "i860 clocks" in r["quantity"]]
    assert clocks and all(r["source"] == "model:i860" for r in clocks)
    ops = [r for r in rows if r["unit"] == "ops"]
    assert all(r["source"] == "golden" for r in ops)
    # the model's shares add up to 100 %
    share = [r["measured"] for r in rows if "share of clocks" in r["quantity"]]
    assert sum(share) == pytest.approx(100.0)


@pytest.mark.parametrize("bad,match", [
    ("nope", "dict"),
    ({"vertex_transform": {}}, "lack stage"),
    ({s: {"mul": -1} for s in b.STAGES}, "mul"),
    ({s: {"add": float("nan")} for s in b.STAGES}, "add"),
    ({s: {"sqrt": "3"} for s in b.STAGES}, "sqrt"),
])
def test_bad_counts(bad, match):
    with pytest.raises(RasterhwError, match=match):
        b.table1_rows(bad)


def test_bad_balance_parameters():
    clk = {s: 1 for s in b.STAGES}
    with pytest.raises(RasterhwError, match="clock_hz"):
        b.balance(clk, clock_hz=0)
    with pytest.raises(RasterhwError, match="n_pipelines"):
        b.balance(clk, n_pipelines=0)
    with pytest.raises(RasterhwError, match="lack"):
        b.balance({"clip": 1})


# ------------------------------------------------------------------ traversal


def _cube_scene() -> Scene:
    """6 quads of a unit cube (one colour per face) plus one triangle with vertex colours."""
    quads = []
    normals = []
    for axis in range(3):
        for sgn in (-1.0, 1.0):
            u, v = [a for a in range(3) if a != axis]
            q = np.zeros((4, 3))
            q[:, axis] = sgn
            q[:, u] = [-1, 1, 1, -1]
            q[:, v] = [-1, -1, 1, 1]
            quads.append(q + [3.0, -2.0, 0.5])
            n = np.zeros((4, 3))
            n[:, axis] = sgn
            normals.append(n)
    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    pos, nv = Scene.pad(quads + [tri])
    nrm, _ = Scene.pad(normals + [np.tile([0.0, 0, 1], (3, 1))])
    face_cols = [np.tile(c, (4, 1)) for c in np.linspace(0.1, 0.9, 18).reshape(6, 3)]
    col, _ = Scene.pad(face_cols + [np.eye(3)])
    return Scene(name="cube", positions=pos, normals=nrm, colours=col, nverts=nv)


def test_record_size_and_bandwidth():
    assert tv.RECORD_BYTES == 36
    assert tv.traversal_bandwidth() == 100_000 * 108 == 10.8e6
    with pytest.raises(RasterhwError):
        tv.traversal_bandwidth(float("nan"))


def test_scene_hierarchy_round_trip():
    scene = _cube_scene()
    css = tv.css_from_scene(scene, polys_per_object=4)
    out = css.post(0)
    expect, src = tv.scene_triangles(scene)
    assert out.records.dtype == np.float32 and out.records.shape == (3 * 13, 9)
    assert out.n_triangles == 6 * 2 + 1 and out.nbytes == 108 * 13
    assert np.array_equal(out.source, src)
    np.testing.assert_allclose(out.triangles(), expect, rtol=0, atol=1e-6)
    # two objects under the root, faces of one colour bound via colour attributes
    assert out.stats["execute"] == 2 and out.stats["structures"] == 3
    assert out.stats["colour"] == 6 and out.stats["polygon3"] == 7


def test_instancing_attributes_and_scoping():
    css = tv.CSS()
    tri = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    nrm = np.tile([0.0, 0, 1], (3, 1))
    css.polygon3(1, tri, nrm, tag=7)  # the instanced part: colour from the caller
    css.colour(1, [0, 0, 1])  # changes colour only inside the child (after its polygon)
    css.colour(0, [1, 0, 0])
    m = np.eye(4)
    m[:3, 3] = [10, 0, 0]
    css.local_transform(0, m)
    css.execute(0, 1)
    s = np.diag([2.0, 2.0, 2.0, 1.0])
    css.local_transform(0, s, "post")  # translate(10) @ scale(2): scale first, then move
    css.execute(0, 1)
    css.polygon3(0, tri, nrm, tag=8)  # back in the root: red again, same composite transform
    out = css.post(0)
    v = out.triangles()
    assert out.n_triangles == 3 and out.source.tolist() == [7, 7, 8]
    np.testing.assert_allclose(v[0, :, :3], tri + [10, 0, 0])
    np.testing.assert_allclose(v[1, :, :3], 2 * tri + [10, 0, 0])
    np.testing.assert_allclose(v[2, :, :3], 2 * tri + [10, 0, 0])
    np.testing.assert_allclose(v[:, :, 6:], np.tile([1.0, 0, 0], (3, 3, 1)))
    # normals by the inverse transpose: a uniform scale by 2 halves them (not re-normalised)
    np.testing.assert_allclose(v[1, :, 3:6], nrm / 2)
    assert out.stats["max_stack"] == 1


def test_quad_fans_into_two_triangles_with_vertex_colours():
    css = tv.CSS()
    q = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    col = np.eye(4)[:, :3]
    css.polygon3(5, q, np.tile([0.0, 0, 1], (4, 1)), col)
    out = css.post(5)
    assert out.records.shape == (6, 9)
    np.testing.assert_allclose(out.records[:, :3], q[[0, 1, 2, 0, 2, 3]])
    np.testing.assert_allclose(out.records[:, 6:], col[[0, 1, 2, 0, 2, 3]])


def test_traversal_errors():
    css = tv.CSS()
    with pytest.raises(RasterhwError, match="no structure"):
        css.post(3)
    css.execute(0, 9)
    with pytest.raises(RasterhwError, match="missing structure"):
        css.post(0)
    loop = tv.CSS()
    loop.execute(0, 1)
    loop.execute(1, 0)
    with pytest.raises(RasterhwError, match="deeper"):
        loop.post(0)
    with pytest.raises(RasterhwError, match="mode"):
        css.local_transform(0, np.eye(4), "sideways")
    with pytest.raises(RasterhwError, match="4x4"):
        css.local_transform(0, np.eye(3))
    with pytest.raises(RasterhwError, match="singular"):
        css.local_transform(0, np.zeros((4, 4)))
    with pytest.raises(RasterhwError, match="points"):
        css.polygon3(0, np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(RasterhwError, match="NaN"):
        css.polygon3(0, np.full((3, 3), np.nan), np.zeros((3, 3)))
    with pytest.raises(RasterhwError, match="colour"):
        css.colour(0, [1, 2])
    with pytest.raises(RasterhwError, match="polys_per_object"):
        tv.css_from_scene(_cube_scene(), polys_per_object=0)
