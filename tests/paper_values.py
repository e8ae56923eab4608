"""Every ``paper`` cell of a committed report is a number the paper prints: helpers of the
per-machine tests (tests/{sparse,zbm,snu}/test_*_paper.py).

A cell is printed if one of its spellings occurs in the seed's text as a number on its own (no
digit beside it): as is, with a decimal comma (Russian), with thousands separators, or scaled to
the K / M the paper writes (115.8K, 7.4M, 12 Mpixel). A value the paper prints in words ("half",
"five", "100 %") is listed by the test with the seed's words, which must occur.
"""

from __future__ import annotations

import re
from pathlib import Path

from rasterhw.sim.report.rows import parse_table

ROOT = Path(__file__).resolve().parents[1]
SEEDS = Path("/work/shared/seeds") if Path("/work/shared/seeds").is_dir() else ROOT.parent / "shared" / "seeds"


def seed_text(prefix: str) -> str:
    (path,) = SEEDS.glob(f"{prefix}_*.txt")
    return path.read_text()


def committed_rows(system: str) -> list[dict]:
    return parse_table((ROOT / "docs" / "reproduction" / f"{system}.md").read_text())


def _spellings(v: float) -> set[str]:
    out = set()
    for scale in (1, 1e3, 1e6):
        x = v / scale
        if x < 0.01 and v != 0:
            continue
        for s in (f"{x:g}", f"{x:.1f}", f"{x:.2f}", f"{x:.3f}"):
            out |= {s, s.replace(".", ",")}
        if x == int(x):
            out |= {f"{int(x):,}", str(int(x))}
    return out


def printed(v: float, text: str) -> bool:
    """Whether ``v`` occurs in ``text`` as a number, in one of its spellings."""
    return any(re.search(rf"(?<![\d.,]){re.escape(s)}(?![\d])", text) for s in _spellings(v))


def unprinted_paper_cells(system: str, prefix: str, words: dict[float, str]) -> list[tuple[str, str]]:
    """(quantity, paper cell) of every committed row whose paper value the seed does not print:
    neither as a number (:func:`printed`) nor in the words ``words`` gives for it."""
    text = seed_text(prefix)
    bad = []
    for r in committed_rows(system):
        cell = r["paper"]
        if cell in ("—", ""):
            continue
        v = float(cell.replace(",", ""))
        if printed(v, text):
            continue
        w = words.get(v)
        if w is not None and w in text:
            continue
        bad.append((r["quantity"], cell))
    return bad


def paper_cells(system: str, needle: str) -> list[str]:
    """The paper cells of the committed rows whose quantity contains ``needle``."""
    return [r["paper"] for r in committed_rows(system) if needle in r["quantity"]]


def derived_with_paper_cells(system: str, needles: tuple[str, ...]) -> list[tuple[str, list[str]]]:
    """(needle, cells) for every derived-row needle that matches no committed row or whose rows hold a
    paper cell (a derived value belongs in ``formula``)."""
    out = []
    for needle in needles:
        cells = paper_cells(system, needle)
        if not cells or set(cells) != {"—"}:
            out.append((needle, cells))
    return out


def unprinted_module_values(module, prefix: str, words: dict, skip: tuple[str, ...] = ()) -> list[tuple[str, float]]:
    """(name, value) of every number of a ``paper.py`` module's ``PAPER_*`` constants (nested dicts
    and tuples opened) the seed does not print (nor ``words`` for it), and (name, None) for a
    constant without a quote in the module's ``QUOTES``."""
    text = seed_text(prefix)

    def numbers(v):
        if isinstance(v, dict):
            return [x for t in v.values() for x in numbers(t)]
        if isinstance(v, tuple):
            return [x for t in v for x in numbers(t)]
        return [v]

    bad = []
    for name in module.__all__:
        if name == "QUOTES" or name in skip:
            continue
        bad += [(name, x) for x in numbers(getattr(module, name))
                if not printed(x, text) and words.get(x, "\0") not in text]
        if name not in module.QUOTES:
            bad.append((name, None))
    return bad


#: the seed of each machine's ``golden_model/NAME/paper.py``
SEED_OF = {"experts": "000", "vzbuf": "001", "sparse": "002", "zbm": "003", "snu": "004"}


def _squash(s: str) -> str:
    """``s`` without white space and the quote marks 《》 the quotes keep or drop."""
    return "".join(s.split()).replace("《", "").replace("》", "")


def unquoted(module, prefix: str) -> list[tuple[str, str]]:
    """(name, piece) of every quote of a ``paper.py`` module's ``QUOTES`` that does not stand in seed
    ``prefix``: each piece between the ellipses (``...``, and `` / `` between table rows) must occur
    in the seed, spaces aside; (name, "") for a quote with no location or words, or whose name the
    module does not export."""
    text = _squash(seed_text(prefix))
    bad = []
    for name, (loc, quote) in module.QUOTES.items():
        if not (loc and quote and name in module.__all__):
            bad.append((name, ""))
            continue
        for piece in quote.replace(" / ", "...").split("..."):
            if _squash(piece) and _squash(piece) not in text:
                bad.append((name, piece))
    return bad
