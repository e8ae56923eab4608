"""docs/architecture.md's naming table and the registry agree with the tree."""

from __future__ import annotations

import re
from pathlib import Path

from rasterhw.sim import registry

ROOT = Path(__file__).resolve().parents[1]


def test_every_file_in_the_naming_table_exists():
    text = (ROOT / "docs" / "architecture.md").read_text()
    table = text[text.index("## Naming table"):text.index("## Testbenches and engines")]
    paths = set(re.findall(r"`((?:hdl|golden_model|sim|tests|cocotb_tests|docs)/[\w/.]+\.(?:py|md))`", table))
    assert len(paths) > 20
    missing = sorted(p for p in paths if not (ROOT / p).exists())
    assert not missing, f"named in docs/architecture.md but not in the tree: {missing}"


def test_every_machine_has_a_folder_in_every_tree():
    ms = registry.machines()
    assert {"snu", "zbm"} <= set(ms)
    for name, m in ms.items():
        for tree in ("golden_model", "sim", "tests"):
            assert (ROOT / tree / name).is_dir(), f"{name}: no {tree}/{name}/"
        assert (ROOT / "docs" / f"{name}.md").exists(), f"{name}: no docs/{name}.md"
        for ref in [*m.blocks.values(), *(a.render for a in m.archs), *(s.simulate for s in m.sims),
                    *([m.report] if m.report else []), *([m.bench] if m.bench else [])]:
            assert callable(registry.load(ref)), ref
        assert (ROOT.parent / "shared" / "seeds" / m.seed).exists() or not (ROOT.parent / "shared").exists()


def _import_graph() -> tuple[dict[str, set[str]], dict[str, list[str]]]:
    """Module -> the package modules it imports (inside functions too), and module -> the
    ``"rasterhw...:attr"`` strings it holds."""
    import ast

    trees = {"hdl": "rasterhw.hdl", "golden_model": "rasterhw.golden_model", "sim": "rasterhw.sim"}
    mods = {}
    for top, pkg in trees.items():
        for p in (ROOT / top).rglob("*.py"):
            if "__pycache__" in p.parts:
                continue
            parts = [pkg, *p.relative_to(ROOT / top).with_suffix("").parts]
            if parts[-1] == "__init__":
                parts.pop()
            mods[".".join(parts)] = p
    graph, strings = {}, {}
    for m, p in mods.items():
        tree = ast.parse(p.read_text(encoding="utf-8"))
        names = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names |= {a.name for a in node.names}
            elif isinstance(node, ast.ImportFrom) and node.module and not node.level:
                names |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
        deps = set()
        for n in names:
            parts = n.split(".")
            while parts and ".".join(parts) not in mods:
                parts.pop()
            d = ".".join(parts)
            if parts and d != m and not m.startswith(d + "."):
                deps.add(d)
        graph[m] = deps
        strings[m] = [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str)
                      and n.value.startswith("rasterhw.")]
    return graph, strings


def test_no_import_cycles_and_shared_code_knows_no_machine():
    graph, strings = _import_graph()
    machines = set(registry.machines())

    def machine_of(mod: str) -> bool:
        return any(part in machines for part in mod.split(".")[1:])

    leaks = [(m, d) for m, deps in graph.items() if not machine_of(m) and m != "rasterhw.sim.registry"
             for d in deps if machine_of(d)]
    leaks += [(m, s) for m, ss in strings.items() if not machine_of(m) and m != "rasterhw.sim.registry"
              for s in ss if machine_of(s.split(":")[0])]
    assert not leaks, f"shared modules that name a machine package: {leaks}"
    # a cycle: a module that reaches itself again (depth-first, imports inside functions counted)
    state, cycles = {}, []

    def visit(m, path):
        state[m] = 1
        for d in graph.get(m, ()):
            if state.get(d) == 1:
                cycles.append(path[path.index(d):] + [d])
            elif d not in state:
                visit(d, path + [d])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [m])
    assert not cycles, f"import cycles: {cycles[:3]}"


def test_every_registered_module_is_in_the_naming_table():
    """Every module a machine registers (blocks, archs, scene runs, testbenches, soak rounds,
    proofs) is named in docs/architecture.md's naming table."""
    text = (ROOT / "docs" / "architecture.md").read_text()
    table = text[text.index("## Naming table"):text.index("## Testbenches and engines")]
    missing = []
    for m in registry.machines().values():
        refs = [*m.blocks.values(), *(a.render for a in m.archs), *(s.simulate for s in m.sims),
                *m.testbenches.values(), *m.soak.values(), *m.proofs.values()]
        for ref in refs:
            path = ref.split(":")[0].removeprefix("rasterhw.").replace(".", "/") + ".py"
            if f"`{path}`" not in table:
                missing.append((m.name, path))
    assert not missing, f"registered but not in the naming table: {sorted(set(missing))}"


def test_docs_name_only_modules_and_names_that_exist():
    """Every ``from rasterhw... import a, b``, ``import rasterhw...`` and ``-m rasterhw...`` in
    docs/*.md resolves (the snippets' imports; running them is not checked here)."""
    import importlib

    bad = []
    for doc in sorted((ROOT / "docs").glob("*.md")):
        for k, line in enumerate(doc.read_text().splitlines(), 1):
            for m in re.finditer(r"(?:from|import|-m) (rasterhw(?:\.\w+)+)(?: import ([\w, ]+))?", line):
                try:
                    mod = importlib.import_module(m.group(1))
                except ImportError:
                    parent, _, attr = m.group(1).rpartition(".")
                    try:   # `import rasterhw.pkg.mod as x` where mod is an attribute
                        if hasattr(importlib.import_module(parent), attr):
                            continue
                    except ImportError:
                        pass
                    bad.append(f"{doc.name}:{k} {m.group(1)}")
                    continue
                for name in (n.strip().split(" ")[0] for n in (m.group(2) or "").split(",")):
                    if name and not hasattr(mod, name):
                        try:
                            importlib.import_module(f"{m.group(1)}.{name}")
                        except ImportError:
                            bad.append(f"{doc.name}:{k} {m.group(1)}.{name}")
    assert not bad, f"docs name what does not exist: {bad}"


SIM_LAYERS = ["top", "engines", "flow", "report", "cli"]   # each may import only those before it


def _sim_layer(mod: str) -> int | None:
    parts = mod.split(".")
    if parts[:2] != ["rasterhw", "sim"] or len(parts) < 3:
        return None
    if parts[2] in SIM_LAYERS:
        return SIM_LAYERS.index(parts[2])
    if len(parts) == 3 and parts[2] not in registry.machines():
        return 0
    return None   # a machine folder: may use any layer but cli


def test_sim_layers_import_only_downwards():
    graph, _ = _import_graph()
    upward = [(m, d) for m, deps in graph.items() for d in deps
              if _sim_layer(m) is not None and _sim_layer(d) is not None and _sim_layer(d) > _sim_layer(m)]
    machines = set(registry.machines())
    upward += [(m, d) for m, deps in graph.items() for d in deps
               if any(p in machines for p in m.split(".")[2:3]) and _sim_layer(d) == SIM_LAYERS.index("cli")]
    assert not upward, f"sim/ modules that import a layer above their own: {sorted(upward)}"
