"""Mutation coverage (sim/flow/mutate.py, ``rasterhw mutate``): Yosys plants faults behind one
control input, one Verilator build serves every mutant, the block's testbench judges each."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner
from rasterhw.sim.cli.main import cli, main
from rasterhw.sim.flow import mutate as M
from test_json_style import style_problems

LINE = ("mutate -ctrl mutsel 6 4 -mode const1 -module rasterhw_bench -cell $flatten\\dut.$ternary$bench.v:455$13 "
        "-port A -portbit 62 -src bench.v:455.3-455.9 -src /x/t50-pkg/rasterhw/hdl/zbm/merger.py:35")


def test_a_mutation_line_names_its_amaranth_source_and_its_fault():
    (m,) = M.parse_mutations("# a comment\n" + LINE + "\n")
    assert m["mutant"] == 4 and m["src"] == ["hdl/zbm/merger.py:35"]
    assert m["mutation"] == "const1 on $flatten\\dut.$ternary$bench.v:455$13 port A bit 62"


@pytest.mark.heavy
@pytest.mark.cocotb
def test_the_testbench_kills_a_mutant_that_mutant_0_passes():
    """zbm-merger, 3 mutants: mutant 0 (no fault) passes its testbench; a planted fault fails it
    (words differ from the golden model, or a run never finishes), in the one build."""
    n = 3
    bench = M.mutated_bench("zbm-merger", {}, mutants=n, seed=1)
    assert [m["mutant"] for m in bench["mutations"]] == [1, 2, 3]
    assert "$value$plusargs(\"mutsel=%d\", mutsel)" in bench["design"][1]["rasterhw_bench.v"]
    base = M.mutant_result("zbm-merger", "{}", n, 1, 0)
    assert base == {"mutant": 0, "killed": False, "why": ""}
    runs = [M.mutant_result("zbm-merger", "{}", n, 1, k) for k in (1, 2, 3)]
    dead = [r for r in runs if r["killed"]]
    assert dead, runs
    assert all(("differ from the golden model" in r["why"]) or ("did not finish" in r["why"]) for r in dead)
    # the same seed gives the same mutants
    assert M.mutated_bench("zbm-merger", {}, mutants=n, seed=1)["mutations"] == bench["mutations"]


@pytest.mark.heavy
@pytest.mark.cocotb
def test_campaign_json_adds_up(tmp_path):
    out = CliRunner().invoke(cli, ["mutate", "zbm-merger", "--mutants", "3", "--seed", "1", "--json",
                                   "--store", str(tmp_path)])
    assert out.exit_code == 0, out.output
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert r["mutants"] == 3 and r["baseline_passed"] is True
    assert r["killed"] + r["equivalent"] + r["survived"] == 3
    assert r["score"] == pytest.approx(r["killed"] / (3 - r["equivalent"]), abs=1e-4)
    assert all(s["src"] and s["mutation"] for s in r["survivors"])
    assert not style_problems(r)   # the JSON conventions (docs/architecture.md, JSON output)
    again = CliRunner().invoke(cli, ["mutate", "zbm-merger", "--mutants", "3", "--seed", "1", "--json",
                                     "--store", str(tmp_path)])
    assert json.loads(again.stdout.strip().splitlines()[-1])["reused"] == 4   # mutants 0..3 from the store


@pytest.mark.parametrize("args, msg", [
    (["nope"], "no testbench for block 'nope'"),
    (["zbm-merger", "--mutants", "0"], "--mutants must be between 1"),
    (["zbm-merger", "-p", "foo=1"], "no parameter 'foo'"),
    (["zbm-merger", "--scheduler", "bogus"], "--scheduler must be"),
    (["zbm-merger", "--seed", "-1"], "--seed must be between"),
])
def test_bad_input_is_one_line_and_exit_2(capsys, args, msg):
    with pytest.raises(SystemExit) as e:
        main(["mutate", *args])
    out = capsys.readouterr()
    lines = [ln for ln in out.err.splitlines() if ln.strip()]
    assert e.value.code == 2 and out.out == "" and len(lines) == 1 and lines[0].startswith("error: ")
    assert msg in lines[0]


def test_help_says_what_it_does():
    out = CliRunner().invoke(cli, ["mutate", "--help"])
    assert out.exit_code == 0 and "--mutants" in out.output and "--scheduler" in out.output


def test_all_takes_every_block_of_verilog_list_at_its_stated_small_configuration():
    from rasterhw.sim import registry
    from rasterhw.sim.engines.verilog import block_names

    configs = M.all_configs()
    assert sorted(configs) == sorted(block_names())
    assert all(configs[b] == registry.flow(b).small for b in configs)


def test_all_refuses_an_unknown_block_before_any_work():
    with pytest.raises(M.RasterhwError, match="no testbench for block 'nope'"):
        M.campaign_all(mutants=1, blocks=["nope"])


def test_a_block_not_built_within_the_budget_is_listed_with_why():
    r = M.campaign_all(mutants=1, blocks=["zbm-merger", "experts-dmm"], budget_s=1e-9)
    assert [b["block"] for b in r["blocks"]] == ["zbm-merger", "experts-dmm"]
    assert all(b["score"] is None and "not built within the campaign's time budget" in b["error"] for b in r["blocks"])
    assert r["computed"] == 0


@pytest.mark.heavy
def test_a_survivor_on_a_bit_no_output_depends_on_is_proven_equivalent_and_a_killed_one_is_not():
    """Item 2: Yosys's equivalence flow (equiv_make / equiv_simple / equiv_induct) over the ports of
    the block as its testbench runs it. zbm-pixel at its small configuration, 30 mutants, seed 1:
    mutant 1 ties bit 7 of the rounding add ``value + 2**23`` (``hdl/zbm/pixel.py:45``) to 0, a bit
    the ``>> 24`` drops: proven equivalent, so no testbench could kill it; mutant 4 (killed by the
    testbench) is not."""
    p = json.dumps(M.all_configs()["zbm-pixel"], sort_keys=True)
    cmds = {mu["mutant"]: mu["command"] for mu in M.mutated_bench("zbm-pixel", json.loads(p), mutants=30,
                                                                        seed=1)["mutations"]}
    assert "-portbit 7 " in cmds[1] and "pixel.py:45" in cmds[1]
    assert M.mutant_result("zbm-pixel", p, 30, 1, 4)["killed"]
    assert M.equivalence("zbm-pixel", p, 30, 1, 1)["equivalence"] == "equivalent"
    assert M.equivalence("zbm-pixel", p, 30, 1, 4)["equivalence"] == "not proven"
