"""docs/architecture.md's naming table and the registry agree with the tree."""

from __future__ import annotations

import re
from pathlib import Path

from rasterhw.sim import registry

ROOT = Path(__file__).resolve().parents[1]


def test_every_file_in_the_naming_table_exists():
    text = (ROOT / "docs" / "architecture.md").read_text()
    table = text[text.index("## Naming table"):text.index("## Verification harness")]
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
