"""``rasterhw prove --all`` (sim/flow/stream_proof.py): the stream rules of a block proved, and shown
to fail on a mutant of ``rasterhw mutate`` that its testbench kills too."""

from __future__ import annotations

import pytest
from rasterhw.sim.cli.main import main
from rasterhw.sim.flow import mutate as M
from rasterhw.sim.flow.stream_proof import plant, stream_proof

#: ``rasterhw mutate experts-dmm -p depth=16 --mutants 40 --seed 1``: mutant 40 inverts the DMM/P's
#: output-valid register (``offering``, the bench's ``o__valid``)
BLOCK, PARAMS, N, SEED, MUTANT = "experts-dmm", {"depth": 16}, 40, 1, 40


@pytest.mark.heavy
@pytest.mark.cocotb
def test_a_mutant_fails_both_its_testbench_and_its_proof():
    bench = M.mutated_bench(BLOCK, PARAMS, mutants=N, seed=SEED)
    (mu,) = [m for m in bench["mutations"] if m["mutant"] == MUTANT]
    assert "-port Q" in mu["command"] and "-wire o__valid" in mu["command"] and "-mode inv" in mu["command"]
    # the testbench: mutant 0 passes, the mutant is killed
    params = '{"depth": 16}'
    assert M.mutant_result(BLOCK, params, N, SEED, 0)["killed"] is False
    assert M.mutant_result(BLOCK, params, N, SEED, MUTANT)["killed"] is True
    # the proof: the unmutated block passes, the same fault planted in the proof's netlist fails it
    good = stream_proof(BLOCK, PARAMS)
    assert good["passed"] is True and good["latency"] is not None and good["depth"] >= good["latency"]
    extra = plant(BLOCK, mu["command"], PARAMS)
    assert extra and extra[0].startswith("mutate -mode inv -module top -cell ") and "-port Q -portbit 0" in extra[0]
    bad = stream_proof(BLOCK, PARAMS, depth=good["depth"], extra=extra, tag=f"mutant{MUTANT}")
    assert bad["passed"] is False and bad["failed"], bad


def test_a_mutation_not_on_a_named_register_is_not_planted():
    line = ("mutate -ctrl mutsel 5 5 -mode const1 -module rasterhw_bench -cell $flatten\\dut.$or$bench.v:511$51 "
            "-port B -portbit 3 -src /x/hdl/experts/dmm.py:87")
    assert plant(BLOCK, line, PARAMS) is None


@pytest.mark.parametrize("args, msg", [
    (["prove", "--all", "experts-dmm"], "--all proves every block at its own depth"),
    (["prove", "--all", "--depth", "3"], "--all proves every block at its own depth"),
    (["prove"], "name a block (or --all)"),
    (["mutate", "--all", "zbm-merger"], "--all runs every block at its stated small configuration"),
    (["mutate", "--all", "-p", "depth=3"], "--all runs every block at its stated small configuration"),
])
def test_bad_input_is_one_line_and_exit_2(capsys, args, msg):
    with pytest.raises(SystemExit) as e:
        main(args)
    out = capsys.readouterr()
    lines = [ln for ln in out.err.splitlines() if ln.strip()]
    assert e.value.code == 2 and out.out == "" and len(lines) == 1 and lines[0].startswith("error: ")
    assert msg in lines[0]


def test_a_configuration_that_does_not_fit_is_halved_down_to_sizes_of_2():
    from rasterhw.sim.flow.stream_proof import halved

    assert halved({"width": 64, "pn": 2, "aj": "c", "depth": 5}) == {"width": 32, "pn": 2, "aj": "c", "depth": 2}
    assert halved({"n": 3, "colour": False}) is None
