"""``rasterhw sweep`` (sim/flow/sweep.py): the cross product in order, typed and checked
parameters (a bad one is a one-line error, exit 2, before any scheduler is reached), the CSV and
the plots. Runs in this process (``--scheduler serial``) on a golden arch and a tiny HDL run;
the cluster cases are in tests/test_cluster.py."""

from __future__ import annotations

import csv
import json

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.cli.main import main
from rasterhw.sim.flow.sweep import parse_param, plan, run_sweep, write_outputs
from rasterhw.sim.registry import archs

#: nothing listens here: reaching it would be a different error than the ones the tests expect
NOWHERE = "tcp://127.0.0.1:9"


def cli(capsys, *args):
    with pytest.raises(SystemExit) as e:
        main(list(args))
        raise SystemExit(0)
    out = capsys.readouterr()
    return e.value.code, out.out, out.err


def test_plan_is_the_cross_product_in_order():
    tasks, points = plan("render:experts", ["sn=1,2", "pn=4,8,1"], scenes=["c50", "sp5"], size=(32, 16))
    assert points == [{"sn": s, "pn": p} for s in (1, 2) for p in (4, 8, 1) for _ in ("c50", "sp5")]
    assert [t.scene for t in tasks[:2]] == ["c50", "sp5"]
    assert all(t.kind == "render" and t.name == "experts" and t.size == (32, 16) and t.engine is None for t in tasks)
    (t,), _ = plan("zbm", ["schedule=paper"])
    assert t.engine == "verilator" and dict(t.params) == {"schedule": "paper"} and isinstance(t.params[0][1], str)


def test_param_values_are_typed_and_checked():
    opts = archs()["experts"][1].options
    assert parse_param("sn=1, 2,8", opts, "x") == ("sn", [1, 2, 8])
    assert parse_param("aj=none,c", opts, "x") == ("aj", ["none", "c"])
    for bad, why in (("sn=1.5", "integer"), ("sn=", "empty"), ("sn=1,,2", "empty"), ("aj=z", "one of"),
                     ("nope=1", "no parameter"), ("sn", "NAME=V1"), ("sn=2,2", "twice")):
        with pytest.raises(RasterhwError, match=why):
            parse_param(bad, opts, "x")
    with pytest.raises(RasterhwError, match="--engine"):
        plan("render:experts", ["sn=1"], engine="pysim")
    with pytest.raises(RasterhwError, match="unknown sweep target"):
        plan("nothing", ["sn=1"])
    with pytest.raises(RasterhwError, match="unknown scene"):
        plan("render:experts", ["sn=1"], scenes=["no-such-scene"])


@pytest.mark.parametrize("args,msg", [
    (["render:experts", "--param", "sn=x"], "is not an integer"),
    (["render:experts", "--param", "bogus=1"], "no parameter 'bogus'"),
    (["zbm", "--param", "schedule=fast"], "must be one of overlap, paper"),
    (["zbm", "--param", "interleave=1", "--param", "interleave=2"], "given twice"),
    (["zbm"], "--param"),
    (["render:experts", "--param", "sn=1", "--size", "3y4"], "--size"),
])
def test_bad_sweep_is_one_line_exit_2_before_any_scheduler(capsys, args, msg):
    code, out, err = cli(capsys, "sweep", *args, "--scheduler", NOWHERE, "--json")
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2 and out == "" and len(lines) == 1 and lines[0].startswith("error: ") and msg in lines[0], err


def test_bad_scheduler_is_one_line_exit_2(capsys):
    for cmd in (["sweep", "render:experts", "--param", "sn=1"], ["soak", "--block", "zbm"]):
        code, _, err = cli(capsys, *cmd, "--scheduler", "lokal")
        assert code == 2 and err.strip().splitlines()[-1].startswith("error: --scheduler"), err


def test_unreachable_scheduler_is_one_line_exit_2(capsys, monkeypatch):
    import rasterhw.sim.flow.tasks as T

    monkeypatch.setattr(T, "SCHEDULER_CHECK_S", 1.0)
    code, _, err = cli(capsys, "sweep", "render:experts", "--param", "sn=1", "--scene", "c50", "--scheduler",
                       NOWHERE)
    assert code == 2 and "cannot reach the Dask scheduler" in err and "Traceback" not in err, err


def test_sweep_json_csv_and_plots(capsys, tmp_path):
    code, out, err = cli(capsys, "sweep", "render:experts", "--param", "sn=1,4", "--param", "pn=1,2", "--scene", "c50",
                         "--size", "32x32", "--scheduler", "serial", "--store", str(tmp_path / "s"), "--json",
                         "--out", str(tmp_path / "o"))
    assert code == 0, err
    res = json.loads(out)
    assert res["scheduler"] == "serial" and len(res["points"]) == 4
    for p in res["points"]:
        assert (p["sn"], p["pn"]) == (p["params"]["sn"], p["params"]["pn"])
        assert {"wall_s", "worker", "pid", "frame_digest", "operations"} <= set(p)
    # the golden EXPERTS image does not depend on the timing model's Sn x Pn; its op count does
    assert len({p["frame_digest"] for p in res["points"]}) == 1
    assert len({p["frame_op_times"] for p in res["points"]}) > 1
    rows = list(csv.DictReader(open(tmp_path / "o" / "points.csv")))
    assert [(int(r["param.sn"]), int(r["param.pn"])) for r in rows] == [(1, 1), (1, 2), (4, 1), (4, 2)]
    assert rows[3]["frame_op_times"] == str(res["points"][3]["frame_op_times"])
    for name in ("sn.png", "pn.png"):
        assert (tmp_path / "o" / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_hdl_sweep_point_carries_the_block_result(tmp_path):
    res = run_sweep("pxp", ["ranges=static,i"], scenes=["c50"], size=(16, 8), engine="pysim", scheduler="serial",
                    store=tmp_path)
    assert [p["params"] for p in res["points"]] == [{"ranges": "static"}, {"ranges": "i"}]
    for p in res["points"]:
        assert p["block"] == "pxp" and p["engine"] == "pysim" and p["mismatches"] == 0
        assert p["cycles_per_pixel"] == pytest.approx(p["cycles"] / (16 * 8))
        assert "sim_s" not in p     # timings other than wall_s/build_s are left out: points compare equal
    written = write_outputs(res, tmp_path / "out")
    assert [w.name for w in written] == ["points.csv", "ranges.png"]
