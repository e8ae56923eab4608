"""The machine registry: the one place a machine declares what it offers.

Each machine is a package ``rasterhw.sim.<name>`` whose ``machine.py`` defines ``MACHINE``, a
:class:`Machine`.  :func:`machines` finds every such package (no list to edit), so ``rasterhw
render --arch``, ``verilog``, ``sim``, ``report``, ``bench`` and ``demo`` pick up a new machine
as soon as its folder exists.

Everything a machine names is a ``"module:attribute"`` string imported only when used, so a
machine whose optional tools are missing never breaks another machine's command, and
``rasterhw --help`` stays fast.

Contracts of the named callables:

* arch renderer: ``render(scene, width, height, *, arch, **options) -> Rendered``
  (:class:`rasterhw.golden_model.arch.Rendered`); ``options`` are the :class:`Option` values
  the arch declares, already converted;
* verilog block: ``factory(**params) -> wiring.Component`` (ValueError/TypeError on a bad one);
* sim block: ``simulate(scene, width, height, *, engine, progress, **options) -> dict`` (a block
  declares it as a ``sim/engines/scene.py: SceneRun`` and names its ``simulate``) with at
  least the keys of :data:`SIM_KEYS` and optionally ``frame_rgb``;
* report: ``rows(*, engine, progress, out_dir, **known) -> (rows, markdown sections)``;
* bench: ``bench(*, repeat, hdl, progress) -> list of {"name", "value", "unit", "note"}``;
* soak round: ``round(rng, k) -> {"pixels", "mismatches", "run_s", "settings"}`` for round ``k``
  (:mod:`rasterhw.sim.flow.soak`).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from pathlib import Path

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["ENGINES", "SIM_KEYS", "Arch", "Clock", "Flow", "FpgaSweep", "Machine", "Option", "SimBlock", "block_machine",
           "entries", "flow", "load", "machines"]

#: the one list of the command line's simulator names (``--engine`` of ``sim``, ``report``, ``sweep``,
#: ``demo``): Amaranth pysim, plain Verilator, cocotb on Icarus (``sim/engines/``: ``engines.ENGINES``
#: runs them, ``icarus`` being its alias of ``cocotb-icarus``)
ENGINES = ("pysim", "verilator", "icarus")
#: keys every sim block's ``simulate`` returns (``rasterhw sim`` adds the common timing keys from the
#: engine runs: ``sim/cli/jsonout.py: sim_json``)
SIM_KEYS = ("engine", "cycles", "clock_hz", "pixels_compared", "mismatches")


@dataclass(frozen=True)
class Option:
    """A command-line option an arch or sim block takes (``--name``)."""

    name: str                          # python name; the flag is --name with _ -> -
    help: str
    default: object = None
    choices: tuple[str, ...] | None = None
    type: type = str                   # str, int, float, or bool (a --name/--no-name flag)

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")


@dataclass(frozen=True)
class Arch:
    """A golden renderer ``rasterhw render --arch NAME`` can run."""

    name: str
    help: str
    render: str                        # "module:function"
    options: tuple[Option, ...] = ()
    bytes_per_pixel: int = 400         # peak memory per frame pixel (checked before a render starts)
    colour_note: str = ""              # why its RGB differs from the float reference by design (demo page)


@dataclass(frozen=True)
class SimBlock:
    """A scene run through a block's HDL: ``rasterhw sim NAME``."""

    name: str
    help: str
    simulate: str                      # "module:function"
    default_scene: str
    options: tuple[Option, ...] = ()
    bytes_per_pixel: int = 400         # peak memory per frame pixel (checked before a run starts)
    #: keys the driver returns (for its other callers) that repeat a common key of the sim JSON
    #: under another name (``sim/cli/jsonout.py: sim_json`` leaves them out of ``extra``)
    aliases: tuple[str, ...] = ()
    #: option values with which the run gives no frame image (e.g. ``{"coupled": False}``): ``-o`` is
    #: refused with them before any work, not after the run
    no_image: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Clock:
    """A clock the paper names for a block: the Amaranth domain, the paper's words, Hz (None:
    the paper gives no frequency)."""

    domain: str
    what: str
    hz: float | None
    name: str = "clock"                           # short name in row labels ("segment clock")


@dataclass(frozen=True)
class Flow:
    """How the hardware flow (``sim/flow/synth.py``, ``sim/flow/fpga.py``) takes one Verilog block.

    Every field is optional: a block with no entry is synthesised and placed at its defaults."""

    synth: dict = field(default_factory=dict)     # synthesis parameters unless given (the paper's size)
    small: dict = field(default_factory=dict)     # small sizes: tests and ``synth --all --small``
    fpga: dict = field(default_factory=dict)      # sizes ``rasterhw fpga BLOCK`` places unless given
    #: what ``rasterhw report fpga`` places: (params, "full" | "reduced"); ``full`` is the paper's size
    fpga_runs: tuple[tuple[dict, str], ...] = (({}, "full"),)
    clocks: tuple[Clock, ...] = ()                # the clocks the paper names for this block
    demand_from_synth: bool = False               # its full size is measured against the device by synthesis
    #: how ``rasterhw report fpga`` names a parameter's value in a row label: {param: {value: words}}
    labels: dict = field(default_factory=dict)


@dataclass(frozen=True)
class FpgaSweep:
    """A parameter swept in ``rasterhw report fpga`` (one place-and-route run per value, Fmax
    plotted against it)."""

    block: str
    param: str
    values: tuple
    base: dict                                    # the other parameters of every run
    title: str                                    # plot title
    xlabel: str                                   # the swept parameter in words
    note: str = ""                                # one paragraph under the plot


@dataclass(frozen=True)
class Machine:
    """One of the papers' machines and everything it registers."""

    name: str                          # folder name in every tree: hdl/NAME, golden_model/NAME ...
    title: str
    seed: str                          # file in shared/seeds/
    archs: tuple[Arch, ...] = ()
    blocks: dict[str, str] = field(default_factory=dict)   # verilog block -> "module:factory"
    sims: tuple[SimBlock, ...] = ()
    report: str | None = None          # "module:rows"
    bench: str | None = None           # "module:bench"
    soak: dict[str, str] = field(default_factory=dict)     # soak block -> "module:round" (sim/flow/soak.py)
    proofs: dict[str, str] = field(default_factory=dict)   # verilog block -> "module:PROOF" (sim/flow/prove.py)
    flows: dict[str, Flow] = field(default_factory=dict)   # verilog block -> its hardware-flow settings
    testbenches: dict[str, str] = field(default_factory=dict)  # verilog block -> "module:Testbench" (sim/testbench.py)
    ram_modules: dict[str, str] = field(default_factory=dict)  # black-box RAM module -> "module:bits(params)"
    fpga_sweeps: tuple[FpgaSweep, ...] = ()
    fpga_note: str = ""                           # the paper's clocks in words, for the fpga report
    status: str = ""                   # one line for the README / index page
    #: the demo page's headline rows: ``"figure: quantity"`` of rows of its committed report
    #: (``docs/reproduction/NAME.md``), in order; empty: the first measured rows with a paper value
    headline: tuple[str, ...] = ()
    no_hdl: str = ""                   # why the machine has no HDL block (said on the demo page)
    #: ``"module:function"`` ``(scene, width, height) -> dict`` for the demo's cross-machine table when
    #: no sim block gives the frame's cost (keys: ``cycles`` or ``time_s``, ``clock_hz``, ``source``, ``note``)
    frame_cost: str | None = None


def load(ref: str) -> Callable:
    """``"pkg.module:attr"`` -> the attribute (imports the module)."""
    mod, _, attr = ref.partition(":")
    return getattr(importlib.import_module(mod), attr)


@cache
def machines() -> dict[str, Machine]:
    """Every registered machine, by name, in folder order."""
    import rasterhw.sim as sim_pkg

    found: dict[str, Machine] = {}
    for info in sorted(pkgutil.iter_modules(sim_pkg.__path__), key=lambda m: m.name):
        # a package without a machine.py (engines, flow, cli, ...) is not imported to find out:
        # importing it would run its __init__ (the engines' pulls in Amaranth and every engine)
        if not info.ispkg or not (Path(info.module_finder.path) / info.name / "machine.py").is_file():
            continue
        m = importlib.import_module(f"rasterhw.sim.{info.name}.machine").MACHINE
        if m.name != info.name:
            raise RuntimeError(f"rasterhw.sim.{info.name}.machine registers {m.name!r}: names must match")
        found[m.name] = m
    return found


def _by_name(kind: str, what: str) -> dict[str, tuple[Machine, Arch | SimBlock]]:
    """Every machine's ``Machine.<kind>`` (``archs``, ``sims``) by name -> (its machine, the entry);
    a name two machines register is an error."""
    out: dict[str, tuple[Machine, Arch | SimBlock]] = {}
    for m in machines().values():
        for a in getattr(m, kind):
            if a.name in out:
                raise RuntimeError(f"{what} {a.name!r} registered by {out[a.name][0].name} and {m.name}")
            out[a.name] = (m, a)
    return out


def archs() -> dict[str, tuple[Machine, Arch]]:
    """Every arch name -> (its machine, the arch)."""
    return _by_name("archs", "arch")


def entries(kind: str) -> dict[str, str]:
    """Every machine's ``Machine.<kind>`` table (``blocks``, ``soak``, ``proofs``, ``testbenches``)
    merged into one: name -> reference; a name two machines register is an error."""
    out: dict[str, str] = {}
    for m in machines().values():
        for name, ref in getattr(m, kind).items():
            if name in out:
                raise RuntimeError(f"{kind}: {name!r} registered twice")
            out[name] = ref
    return out


def blocks() -> dict[str, str]:
    """Every Verilog block name -> its factory reference."""
    return entries("blocks")


def sim_blocks() -> dict[str, tuple[Machine, SimBlock]]:
    """Every ``rasterhw sim`` block name -> (its machine, the block)."""
    return _by_name("sims", "sim block")


def machine(name: str) -> Machine:
    """The machine called ``name``, or a one-line error naming the known ones."""
    ms = machines()
    if name not in ms:
        raise RasterhwError(f"unknown machine {name!r}; machines: {', '.join(ms)}")
    return ms[name]


def block_machine(block: str) -> Machine:
    """The machine that registers Verilog block ``block``."""
    for m in machines().values():
        if block in m.blocks:
            return m
    raise RasterhwError(f"unknown block {block!r}; blocks: {', '.join(blocks())}")


def flow(block: str) -> Flow:
    """Block ``block``'s hardware-flow settings (its machine's :class:`Flow`, or the defaults)."""
    return block_machine(block).flows.get(block, Flow())
