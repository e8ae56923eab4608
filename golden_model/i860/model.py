"""The i860 XR as an instruction-level timing model: processor facts, programs, two schedulers.

Every parameter of :class:`I860` is a documented fact, cited in :data:`PARAMETERS` (manual
section or data-sheet line); none is solved from a paper's table. Sources:

* PRM: *i860 64-bit Microprocessor Programmer's Reference Manual*, Intel 1989 (order no.
  240329; SNU's ref. [7]). Chapter 2 "Registers" (the floating-point register file), chapter 5
  "Core instructions" (loads, stores, ``fxfr``), chapter 6 "Floating-point instructions"
  (§6.2 pipelined and scalar operations, the dual-operation instructions and their data-path
  control, ``frcp``/``frsqr``), chapter 7 "Dual-instruction mode", appendix "Instruction
  timings".
* DS: *i860 64-bit Microprocessor* data sheet, Intel 1989 (order no. 240296; posted to
  comp.sys.intel by Intel on 1989-03-04): "one integer or control instruction per clock and up
  to two floating-point results per clock", 33.3/40 MHz, 64-bit external bus, 128-bit internal
  data-cache bus.

What a program is: a list of instructions (:class:`Program`), each with its unit (``A`` adder,
``M`` multiplier, ``G`` graphics unit, ``C`` core: loads, stores, branches, integer, ``fxfr``),
its operands (results of earlier instructions, values already in a register, or *named
constants*) and the operation category a paper's count puts it in (``counted``).

Two schedules (:data:`SCHEDULES`):

``compiler``  what a C compiler of the time emitted (our reading; the papers say only "C"):
              the program order, one instruction per clock, *scalar* floating-point
              instructions (each occupies its unit for its whole latency: no pipelining), no
              dual-operation, no dual-instruction mode; every named constant is loaded from
              memory where it is used (``fld.l``), every input float and every result moves
              with its own ``fld.l`` / ``fst.l``.
``assembler`` hand-written code: instructions reordered freely (list scheduling, longest
              remaining path first); *pipelined* instructions whose pipelines advance only
              when an instruction is issued to them (PRM §6.2: the result of a pipelined
              operation comes out of the last stage as the destination of the pipelined
              instruction issued three later; ``push`` instructions -- a pipelined operation on
              ``f0`` -- drain them); dual-operation instructions (one add and one multiply in one
              instruction) only where the data paths allow it (:func:`_pair_legal`);
              dual-instruction mode (one core + one floating-point instruction per clock);
              input floats loaded four at a time (``fld.q``, 128 bits), results stored four at
              a time (``fst.q``); named constants stay in registers; at most
              ``FP_REGISTERS - ZERO_REGISTERS`` = 30 values live in registers, each value over
              that costs a store and a load on the core (a spill).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from rasterhw.golden_model.errors import RasterhwError

__all__ = ["FP_REGISTERS", "I860", "NEWTON_STEPS", "PARAMETERS", "SCHEDULES", "UNITS", "ZERO_REGISTERS",
           "Program", "counts", "schedule"]

UNITS = ("A", "M", "G", "C")  # FP adder, FP multiplier, graphics unit, core
SCHEDULES = ("compiler", "assembler")
#: PRM ch. 2: 32 floating-point registers of 32 bits (f0..f31)
FP_REGISTERS = 32
#: PRM ch. 2: f0 and f1 always read as zero (writes are ignored): 30 registers hold values
ZERO_REGISTERS = 2
#: Newton-Raphson steps after an frcp/frsqr seed for single precision (see PARAMETERS)
NEWTON_STEPS = 2

#: Every parameter of :class:`I860`: field -> (default, source). ``docs/snu_geometry.md`` and
#: ``docs/zbm.md`` print this table; ``tests/snu/test_snu_i860.py`` holds them equal.
PARAMETERS: dict[str, tuple[object, str]] = {
    "add_stages": (3, "PRM §6.2 (pipelined and scalar operations): the floating-point adder has a "
                      "three-stage pipeline; a scalar add returns its result after the 3 stages"),
    "mul_stages": (3, "PRM §6.2: the multiplier has three stages with single-precision sources "
                      "(two with double-precision sources; not used here)"),
    "pipeline_advances_per_instruction": (True, "PRM §6.2: a pipelined instruction's result leaves the "
                      "last stage as the destination of the pipelined instruction of that unit issued "
                      "three later; the pipeline moves only when such an instruction issues"),
    "dual_operation_paths": ("src1, src2, KR/KI, T, M-result, A-result", "PRM ch. 6, dual-operation "
                      "instructions (pfam/pfsm/pfmam/pfmsm) and their data-path-control (DPC) table: two "
                      "register sources and one destination for the pair; the adder can take the "
                      "multiplier's or its own last-stage result, the multiplier the constant KR/KI or "
                      "the adder's result"),
    "dual_instruction": (True, "PRM ch. 7 (dual-instruction mode, the d. prefix): one core and one "
                      "floating-point instruction per clock; DS: 'one integer or control instruction "
                      "per clock and up to two floating-point results per clock'"),
    "graphics_latency": (1, "PRM ch. 6, graphics unit (faddp, faddz): a one-stage pipeline"),
    "core_latency": (1, "PRM ch. 5: core (integer, branch, fxfr, store) instructions take one clock"),
    "load_latency": (2, "PRM ch. 5 and appendix 'Instruction timings': a cached ld/fld has one delay "
                      "clock, its result usable by the second instruction after it"),
    "load_words": (4, "PRM ch. 5: fld.q / fst.q move 128 bits (four single-precision values) in one "
                      "instruction over the 128-bit data-cache bus (DS)"),
    "fp_registers": (FP_REGISTERS, "PRM ch. 2: 32 floating-point registers f0..f31 of 32 bits"),
    "zero_registers": (ZERO_REGISTERS, "PRM ch. 2: f0 and f1 always read as zero, so 30 hold values"),
    "newton_steps": (NEWTON_STEPS, "PRM ch. 6, FRCP/FRSQR: the seed is good to about 2^-7 (relative); "
                      "each Newton step doubles the good bits; 2 steps reach single precision (24 "
                      "bits), 1 step (14 bits) cannot place a vertex on the 1/256-px grid of a "
                      "1280-px line (2^-19): tests/snu/test_snu_i860.py checks it numerically"),
    "bus_bytes_per_cycle": (8, "DS: 64-bit external data bus"),
    "bus_clocks_per_cycle": (2, "DS: a bus cycle takes two clocks (pipelined bus, 160 MB/s at 40 MHz)"),
}


@dataclass(frozen=True)
class I860:
    """Documented i860 XR timing; every field is in :data:`PARAMETERS` (except the clock and the
    feature switches ``dual_instruction``/``dual_operation``, which the schedules choose)."""

    add_stages: int = 3
    mul_stages: int = 3
    graphics_latency: int = 1
    core_latency: int = 1
    load_latency: int = 2
    load_words: int = 4
    fp_registers: int = FP_REGISTERS
    zero_registers: int = ZERO_REGISTERS
    dual_instruction: bool = True
    dual_operation: bool = True
    newton_steps: int = NEWTON_STEPS
    #: the machine's clock (SNU never states it: 40 MHz assumed; ZB/M: 33.3 MHz, its text)
    clock_hz: float = 40e6
    bus_bytes_per_cycle: int = 8
    bus_clocks_per_cycle: int = 2

    def __post_init__(self) -> None:
        for name in ("add_stages", "mul_stages", "graphics_latency", "core_latency", "load_latency",
                     "load_words", "bus_bytes_per_cycle", "bus_clocks_per_cycle"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise RasterhwError(f"{name} must be a positive integer, not {v!r}")
        if isinstance(self.newton_steps, bool) or not isinstance(self.newton_steps, int) or self.newton_steps < 0:
            raise RasterhwError(f"newton_steps must be an integer >= 0, not {self.newton_steps!r}")
        for name in ("fp_registers", "zero_registers"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 0:
                raise RasterhwError(f"{name} must be an integer >= 0, not {v!r}")
        if self.fp_registers - self.zero_registers < 4:
            raise RasterhwError("the register file must hold at least 4 values "
                                f"(fp_registers {self.fp_registers} - zero_registers {self.zero_registers})")
        if not (isinstance(self.clock_hz, (int, float)) and self.clock_hz > 0):
            raise RasterhwError(f"clock_hz must be > 0, not {self.clock_hz!r}")

    @property
    def value_registers(self) -> int:
        """Registers that can hold a value: 32 - 2 (f0, f1 read as zero) = 30."""
        return self.fp_registers - self.zero_registers

    def latency(self, unit: str, kind: str) -> int:
        """Clocks from issue until a *scalar* result (or a core result) can be read."""
        if unit == "A":
            return self.add_stages
        if unit == "M":
            return self.mul_stages
        if unit == "G":
            return self.graphics_latency
        return self.load_latency if kind in ("fld", "ld", "lookup") else self.core_latency


@dataclass
class Program:
    """Instructions with operands. ``ops[i] = (unit, kind, counted, srcs, nreg, const)``:
    ``srcs`` the earlier instructions whose results it reads, ``nreg`` how many operands are
    values already in registers (kept there across the program), ``const`` the name of a
    named-constant operand (a matrix entry, a light vector component) or ``None``; ``counted``
    the category a paper's operation count puts it in (``mul``, ``add``, ``cmp``, ``div``,
    ``sqrt``, ``lookup``, ``cvt``) or ``None`` for work such counts leave out. ``group`` (a
    parallel list) ties input loads / result stores that one ``fld.q``/``fst.q`` can move."""

    ops: list = field(default_factory=list)
    groups: list = field(default_factory=list)
    newton_steps: int = NEWTON_STEPS

    def op(self, unit: str, kind: str, counted: str | None, *srcs, nreg: int = 0, const: str | None = None,
           group: int | None = None) -> int:
        if unit not in UNITS:
            raise RasterhwError(f"unit must be one of {UNITS}, not {unit!r}")
        ids = []
        for s in srcs:
            if s is None:
                nreg += 1
            elif isinstance(s, str):
                if const is not None and const != s:
                    nreg += 1  # a second constant: an ordinary register operand
                else:
                    const = s
            elif isinstance(s, int) and not isinstance(s, bool):
                if not 0 <= s < len(self.ops):
                    raise RasterhwError(f"instruction {len(self.ops)} depends on {s}, which is not before it")
                ids.append(s)
            else:
                raise RasterhwError(f"operand must be an instruction index, None or a constant name, not {s!r}")
        self.ops.append((unit, kind, counted, tuple(ids), nreg, const))
        self.groups.append(group)
        return len(self.ops) - 1

    # counted operations ------------------------------------------------------------------
    def mul(self, a=None, b=None, *, counted: str | None = "mul") -> int:
        return self.op("M", "fmul", counted, a, b)

    def add(self, a=None, b=None, *, counted: str | None = "add") -> int:
        return self.op("A", "fadd", counted, a, b)

    def cmp(self, a=None, b=None) -> int:
        """A compare (adder, sets the condition code) and the core's branch on it."""
        c = self.op("A", "pfgt", "cmp", a, b)
        return self.op("C", "bc", None, c)

    def recip(self, a, counted: str | None = "div") -> int:
        """1/a: an ``frcp`` seed and Newton steps y <- y (2 - a y) (2 mul + 1 add each)."""
        y = self.op("M", "frcp", counted, a)
        for _ in range(self.newton_steps):
            e = self.op("M", "fmul", None, a, y)
            f = self.op("A", "fsub", None, e, "two")
            y = self.op("M", "fmul", None, y, f)
        return y

    def rsqrt(self, a) -> int:
        """1/sqrt(a): ``frsqr`` seed, a/2 once, Newton steps y <- y (1.5 - (a/2) y y) (3 mul + 1 add
        each); counted as the paper's "square root + reciprocal" (sqrt 1 + div 1)."""
        y = self.op("M", "frsqr", "sqrt", a)
        h = self.op("M", "fmul", "div", a, "half")
        for _ in range(self.newton_steps):
            yy = self.op("M", "fmul", None, y, y)
            t = self.op("M", "fmul", None, h, yy)
            f = self.op("A", "fsub", None, t, "three_halves")
            y = self.op("M", "fmul", None, y, f)
        return y

    def lookup(self, idx) -> int:
        """A table lookup indexed by an FP value: ``fxfr`` to the core, then a load."""
        x = self.op("C", "fxfr", None, idx)
        return self.op("C", "fld", "lookup", x)

    def load(self, n: int) -> list[int]:
        """``n`` input floats from memory (one ``fld.l`` each, or ``fld.q`` per four)."""
        g = self._new_group()
        return [self.op("C", "fld", None, group=g) for _ in range(n)]

    def store(self, *vals) -> list[int]:
        """Results to memory (one ``fst.l`` each, or ``fst.q`` per four)."""
        g = self._new_group()
        return [self.op("C", "fst", None, v, group=g) for v in vals]

    def dot3(self, a, b=(None, None, None)) -> int:
        m = [self.mul(a[i], b[i]) for i in range(3)]
        return self.add(self.add(m[0], m[1]), m[2])

    def affine(self, x, rows: int = 4, m: str = "m", t: str = "t") -> list[int]:
        """``rows`` rows of a 3-column matrix times ``x`` plus a translation, in the golden code's
        order (``opcount.affine``): ``((m_r0 x + m_r1 y) + m_r2 z) + t_r``, constants named
        ``m{r}{k}`` / ``t{r}``."""
        return [self.add(self.dot3(x, tuple(f"{m}{r}{k}" for k in range(3))), f"{t}{r}") for r in range(rows)]

    def concat(self, other: Program) -> list[int]:
        base = len(self.ops)
        gbase = self._new_group()
        for (unit, kind, counted, srcs, nreg, const), g in zip(other.ops, other.groups, strict=True):
            self.ops.append((unit, kind, counted, tuple(s + base for s in srcs), nreg, const))
            self.groups.append(None if g is None else g + gbase)
        return list(range(base, base + len(other.ops)))

    def _new_group(self) -> int:
        return 1 + max((g for g in self.groups if g is not None), default=-1)


def counts(p: Program) -> dict:
    """Counted operations by category (what a paper's count covers) and instructions by unit."""
    counted: dict[str, int] = {}
    units = dict.fromkeys(UNITS, 0)
    for unit, _kind, c, *_ in p.ops:
        units[unit] += 1
        if c is not None:
            counted[c] = counted.get(c, 0) + 1
    return {"counted": counted, "units": units, "instructions": len(p.ops)}


# ------------------------------------------------------------------------------ lowering
def _lower(p: Program, mode: str, cpu: I860) -> tuple[list, list[list[int]]]:
    """Instructions as the schedule issues them: ``(unit, kind, srcs, nreg, const, members)``,
    ``members`` the program instructions each one carries out. ``compiler``: every constant
    operand becomes its own ``fld.l`` before the use; ``assembler``: loads and stores of one
    group go four to an instruction."""
    out: list = []
    where: dict[int, int] = {}  # program op -> lowered instruction
    pending: dict[tuple[int, str], int] = {}  # (group, kind) -> index of the open fld.q/fst.q
    for i, ((unit, kind, _c, srcs, nreg, const), g) in enumerate(zip(p.ops, p.groups, strict=True)):
        s = [where[x] for x in srcs]
        if mode == "compiler" and const is not None:
            out.append(["C", "fld", [], 0, None, []])
            s.append(len(out) - 1)
            const = None
        if mode == "assembler" and g is not None and kind in ("fld", "fst"):
            key = (g, kind)
            j = pending.get(key)
            if j is not None and len(out[j][5]) < cpu.load_words:
                out[j][2].extend(x for x in s if x not in out[j][2])
                out[j][5].append(i)
                where[i] = j
                continue
            out.append([unit, kind, list(s), nreg, const, [i]])
            pending[key] = len(out) - 1
            where[i] = len(out) - 1
            continue
        out.append([unit, kind, s, nreg, const, [i]])
        where[i] = len(out) - 1
    return [(u, k, tuple(s), n, c, tuple(m)) for u, k, s, n, c, m in out], [list(m) for *_r, m in out]


def _prio(ins: list, cpu: I860, succ: list[list[int]]) -> list[int]:
    n = len(ins)
    prio = [0] * n
    for i in range(n - 1, -1, -1):
        prio[i] = cpu.latency(ins[i][0], ins[i][1]) + max((prio[j] for j in succ[i]), default=0)
    return prio


def schedule(p: Program, cpu: I860 | None = None, mode: str = "assembler") -> dict:
    """Schedule ``p`` on ``cpu`` as ``mode`` (:data:`SCHEDULES`).

    Returns ``clocks`` (the clock in which the last result is in a register or memory: pipes
    empty at the start, drained at the end), ``issue`` (clock of each lowered instruction),
    ``instructions`` (lowered list, see :func:`_lower`), ``fp_instructions``, ``core_instructions``,
    ``pushes`` (drain instructions), ``dual_ops`` (add+multiply pairs), ``spills`` and
    ``peak_registers`` (values live in registers at the worst clock, named constants included).
    """
    cpu = cpu or I860()
    if mode not in SCHEDULES:
        raise RasterhwError(f"schedule must be one of {SCHEDULES}, not {mode!r}")
    if p.newton_steps != cpu.newton_steps:
        raise RasterhwError(f"program was written for {p.newton_steps} Newton steps, the processor has "
                            f"{cpu.newton_steps}")
    ins, _members = _lower(p, mode, cpu)
    if not ins:
        raise RasterhwError("schedule: the program is empty")
    n = len(ins)
    succ: list[list[int]] = [[] for _ in range(n)]
    for i, (_u, _k, srcs, *_r) in enumerate(ins):
        for s in srcs:
            succ[s].append(i)
    if mode == "compiler":
        return _inorder(ins, succ, cpu)
    return _list(ins, succ, cpu)


def _inorder(ins: list, succ: list[list[int]], cpu: I860) -> dict:
    """Program order, one instruction per clock, scalar FP (a unit busy for its latency)."""
    ready = [0] * len(ins)
    issue = [0] * len(ins)
    free = {"A": 0, "M": 0, "G": 0}
    t = 0
    for i, (u, k, srcs, *_r) in enumerate(ins):
        lat = cpu.latency(u, k)
        start = max([t] + [ready[s] for s in srcs] + ([free[u]] if u in free else []))
        issue[i] = start
        ready[i] = start + lat
        if u in free:
            free[u] = start + lat
        t = start + 1
    fp = sum(1 for u, *_r in ins if u != "C")
    consts = 0
    return {"clocks": max(ready), "issue": issue, "instructions": ins, "fp_instructions": fp,
            "core_instructions": len(ins) - fp, "pushes": 0, "dual_ops": 0, "spills": 0,
            "peak_registers": _peak_inorder(ins, succ, issue, ready) + consts, "via_path": {}}


def _peak_inorder(ins, succ, issue, ready) -> int:
    """Values in FP registers at the worst clock of an in-order schedule (result written until
    its last reader issues)."""
    ev: dict[int, int] = {}
    for i, (u, k, *_r) in enumerate(ins):
        if u == "C" and k not in ("fld",):
            continue
        if not succ[i]:
            continue
        end = max(issue[j] for j in succ[i])
        ev[ready[i]] = ev.get(ready[i], 0) + 1
        ev[end + 1] = ev.get(end + 1, 0) - 1
    live = peak = 0
    for t in sorted(ev):
        live += ev[t]
        peak = max(peak, live)
    return peak


def _pair_legal(a, m, eA, eM, ins, left, kr) -> bool:
    """Whether adder operation ``a`` and multiplier operation ``m`` (instruction indices, or
    ``None`` for a push: a dummy operation that reads no register) fit one dual-operation
    instruction, with ``eA``/``eM`` the results leaving the adder / multiplier pipelines as it
    issues. The data paths (PRM ch. 6, dual-operation instructions, DPC table): the pair reads
    at most two registers (src1, src2); the adder can also take the multiplier's leaving result
    (M-result) or its own (A-result), the multiplier the constant in KR or the adder's leaving
    result; one destination register: of the leaving results at most one is written (a result
    consumed on a path by this pair and by nothing else needs no register)."""
    reads = 0
    used_here: dict[int, int] = {}
    for x, unit in ((a, "A"), (m, "M")):
        if x is None:
            continue
        _u, _k, srcs, nreg, const, _mem = ins[x]
        reads += nreg
        if const is not None and not (unit == "M" and const == kr):
            reads += 1
        for s in srcs:
            if (unit == "A" and s in (eM, eA)) or (unit == "M" and s == eA):
                used_here[s] = used_here.get(s, 0) + 1
            else:
                reads += 1
    if reads > 2:
        return False
    writes = 0
    for e in (eA, eM):
        if e is not None and left[e] - used_here.get(e, 0) > 0:
            writes += 1
    return writes <= 1


def _list(ins: list, succ: list[list[int]], cpu: I860) -> dict:  # noqa: C901 - one scheduler loop
    """Assembler schedule: list scheduling with per-instruction pipelines, data-path-checked
    dual operation, dual-instruction mode, drain pushes and a 30-register file."""
    n = len(ins)
    prio = _prio(ins, cpu, succ)
    INF = 1 << 40
    avail = [INF] * n           # clock from which the value can be read from a register
    issue = [-1] * n
    left = [len(succ[i]) for i in range(n)]   # readers not yet issued
    nsrc_open = [len(ins[i][2]) for i in range(n)]
    pipes = {"A": [None] * cpu.add_stages, "M": [None] * cpu.mul_stages}
    consts = {c for *_r, c, _m in ins if c is not None}
    live: set[int] = set()
    kr = None
    via_path: dict[int, int] = {}
    t = done = pushes = dual_ops = spills = fp_n = core_n = 0
    peak = len(consts)
    spill_work = 0
    end = 0
    waiting = [i for i in range(n) if nsrc_open[i] == 0]
    # registers a value holds: an fld.q brings up to four (kept until its last reader issues)
    weight = [len(ins[i][5]) if ins[i][1] == "fld" else 1 for i in range(n)]

    def src_ok(i, unit, eA, eM, paired):
        path = []
        for s in ins[i][2]:
            if avail[s] <= t:
                continue
            if paired and cpu.dual_operation and ((unit == "A" and s in (eA, eM)) or (unit == "M" and s == eA)):
                path.append(s)
                continue
            return None
        return path

    while done < n or any(x is not None for q in pipes.values() for x in q):
        eA, eM = pipes["A"][0], pipes["M"][0]
        cand = sorted(waiting, key=lambda i: (-prio[i], i))
        fp_ready = {"A": [], "M": [], "G": []}
        fp_path = {"A": [], "M": []}
        core_ready = []
        for i in cand:
            u = ins[i][0]
            if u == "C":
                if src_ok(i, u, eA, eM, False) is not None:
                    core_ready.append(i)
            elif u == "G":
                if src_ok(i, u, eA, eM, False) is not None:
                    fp_ready["G"].append(i)
            else:
                if src_ok(i, u, eA, eM, False) is not None:
                    fp_ready[u].append(i)
                elif src_ok(i, u, eA, eM, True) is not None:
                    fp_path[u].append(i)
        # register pressure: when the file is (nearly) full, issue first what frees registers
        # (an operation that is the last reader of its sources), as a programmer would
        busy = len(consts) + sum(weight[v] for v in live if left[v] > 0) + sum(
            1 for q in pipes.values() for x in q if x is not None)
        if busy >= cpu.value_registers - 1:
            def frees(i):
                return sum(1 for x in ins[i][2] if left[x] == 1) >= 1
            for u in ("A", "M", "G"):
                keep = [i for i in fp_ready[u] if frees(i)]
                fp_ready[u] = keep or ([] if any(frees(i) for v in fp_ready.values() for i in v) else fp_ready[u])
            for u in ("A", "M"):
                keep = [i for i in fp_path[u] if frees(i)]
                fp_path[u] = keep or fp_path[u]
        # --- the floating-point instruction of this clock
        choice = None  # (score, a, m, g, pushA, pushM)
        realA = eA is not None or any(x is not None for x in pipes["A"])
        realM = eM is not None or any(x is not None for x in pipes["M"])
        if cpu.dual_operation:
            adds = (fp_ready["A"] + fp_path["A"])[:6] + [None]
            muls = (fp_ready["M"] + fp_path["M"])[:6] + [None]
            for a in adds:
                for m in muls:
                    if a is None and m is None:
                        continue
                    if a is None and not realA or m is None and not realM:
                        continue  # a push only where it moves a real result
                    if a is not None and src_ok(a, "A", eA, eM, True) is None:
                        continue
                    if m is not None and src_ok(m, "M", eA, eM, True) is None:
                        continue
                    if not _pair_legal(a, m, eA, eM, ins, left, kr):
                        continue
                    score = (prio[a] if a is not None else 0) + (prio[m] if m is not None else 0)
                    if m is not None and ins[m][4] is not None and ins[m][4] == kr:
                        score += 0.5  # keep KR: the next multiply by the same constant reads no register
                    if choice is None or score > choice[0]:
                        choice = (score, a, m, None)
        singles = [(prio[i], u, i) for u in ("A", "M", "G") for i in fp_ready[u][:1]]
        for sc, u, i in singles:
            if choice is None or sc > choice[0]:
                choice = (sc, i if u == "A" else None, i if u == "M" else None, i if u == "G" else None,
                          u)
        if choice is None and (realA or realM):
            # nothing to issue but results inside a pipe: push the one whose exit is real first
            u = "A" if eA is not None else "M" if eM is not None else ("A" if realA else "M")
            choice = (0, None, None, None, "push" + u)
        core_pick = None
        if spill_work:
            core_pick = "spill"
        else:
            # a load only while its values fit the register file (values live, in flight in the
            # pipes, and the named constants): hand-written code loads no earlier than that
            for c in core_ready:
                if ins[c][1] == "fld" and busy + len(ins[c][5]) > cpu.value_registers:
                    continue
                core_pick = c
                break
            if core_pick is None and core_ready and choice is None:
                core_pick = core_ready[0]  # nothing else can move: load anyway (and spill)
        if not cpu.dual_instruction and choice is not None and core_pick is not None:
            fp_score = choice[0]
            cp = 1 << 30 if core_pick == "spill" else prio[core_pick]
            if cp > fp_score:
                choice = None
            else:
                core_pick = None
        # --- issue
        issued_fp = False
        if choice is not None:
            _sc, a, m, g = choice[:4]
            tag = choice[4] if len(choice) > 4 else "pair"
            adv = set()
            if tag == "pair":
                adv = {"A", "M"}
                if a is not None and m is not None:
                    dual_ops += 1
            elif tag in ("A", "M"):
                adv = {tag}
            elif tag == "pushA":
                adv = {"A"}
            elif tag == "pushM":
                adv = {"M"}
            paired = tag == "pair"
            for x, u in ((a, "A"), (m, "M")):
                if x is None:
                    continue
                for s in src_ok(x, u, eA, eM, paired) or []:
                    via_path[x] = s
            if m is not None and ins[m][4] is not None:
                kr = ins[m][4]
            newvals = {"A": a, "M": m}
            for u in adv:
                out = pipes[u].pop(0)
                pipes[u].append(newvals[u])
                if out is not None:
                    avail[out] = t + 1
                    end = max(end, t + 1)
                    live.add(out)
            if g is not None:
                avail[g] = t + cpu.graphics_latency
                end = max(end, avail[g])
                live.add(g)
            issued_fp = True
            fp_n += 1
            if a is None and m is None and g is None:
                pushes += 1
            elif paired and (a is None or m is None):
                pushes += 1
            for x in (a, m, g):
                if x is not None:
                    _issue(x, t, ins, issue, left, live, succ, nsrc_open, waiting)
                    done += 1
        if core_pick == "spill":
            spill_work -= 1
            core_n += 1
        elif core_pick is not None:
            c = core_pick
            avail[c] = t + cpu.latency(ins[c][0], ins[c][1])
            end = max(end, avail[c])
            if ins[c][1] in ("fld",) or succ[c]:
                if ins[c][1] == "fld":
                    live.add(c)
            _issue(c, t, ins, issue, left, live, succ, nsrc_open, waiting)
            done += 1
            core_n += 1
        elif not issued_fp and done < n:
            pass  # a stall: every ready instruction waits for a result
        nlive = len(consts) + sum(weight[v] for v in live if left[v] > 0)
        if nlive > cpu.value_registers:
            over = nlive - cpu.value_registers
            spills += over
            spill_work += 2 * over  # a store now and a load before the use, on the core
            # the spilled values leave the register file (their reload is assumed in time)
            freed = 0
            for v in sorted((v for v in live if left[v] > 0), key=lambda v: min(
                    (prio[j] for j in succ[v] if issue[j] < 0), default=0)):
                if freed >= over:
                    break
                live.discard(v)
                freed += weight[v]
        peak = max(peak, min(nlive, cpu.value_registers))
        live = {v for v in live if left[v] > 0}
        t += 1
        if t > 100 * n + 1000:
            raise RasterhwError("schedule did not finish (internal error)")
    end = max(end, t + spill_work)
    return {"clocks": end, "issue": issue, "instructions": ins, "fp_instructions": fp_n,
            "core_instructions": core_n, "pushes": pushes, "dual_ops": dual_ops, "spills": spills,
            "peak_registers": peak, "via_path": via_path}


def _issue(x, t, ins, issue, left, live, succ, nsrc_open, waiting) -> None:
    issue[x] = t
    waiting.remove(x)
    for s in ins[x][2]:
        left[s] -= 1
    for j in succ[x]:
        nsrc_open[j] -= 1
        if nsrc_open[j] == 0:
            waiting.append(j)
