"""A wave snapshot as SVG: the clock, the cycle counter and the stream ports of a short trace
(a VCD written with ``--waves`` and a trace window, ``sim/engines/waves.py``), drawn the way a
wave viewer draws them -- one bit as a line, a vector as boxes with its value in hex -- for the
demo page (``sim/report/demo.py``). Shared: the signals are the ones the trace's GTKWave save
file would show (:func:`rasterhw.sim.engines.waves.stream_signals`), no machine is named here."""

from __future__ import annotations

from html import escape
from pathlib import Path

from rasterhw.sim.engines import waves

__all__ = ["wave_svg"]

_ROW, _NAME_W, _STEP_W = 22, 230, 24


def _changes(vcd: Path, wanted: dict[str, str]) -> tuple[dict[str, list[tuple[int, str]]], list[int]]:
    """Value changes ``{GTKWave name: [(time, value bits), ...]}`` of the variables ``wanted``
    (GTKWave name -> VCD name ``scope.name``) and the times of the trace's time steps."""
    ids: dict[str, list[str]] = {}
    scope: list[str] = []
    out: dict[str, list[tuple[int, str]]] = {n: [] for n in wanted}
    by_vcd = {v: n for n, v in wanted.items()}
    times: list[int] = []
    t = 0
    with open(vcd) as f:
        header = True
        for ln in f:
            tok = ln.split()
            if header:
                if tok[:1] == ["$scope"] and len(tok) > 2:
                    scope.append(tok[2])
                elif tok[:1] == ["$upscope"]:
                    scope.pop()
                elif tok[:1] == ["$var"] and len(tok) >= 5:
                    name = by_vcd.get(".".join((*scope, tok[4])))
                    if name is not None:
                        ids.setdefault(tok[3], []).append(name)
                elif "$enddefinitions" in tok:
                    header = False
                continue
            if not tok:
                continue
            c = tok[0][0]
            if c == "#":
                t = int(tok[0][1:])
                times.append(t)
            elif c in "bB" and len(tok) > 1:
                for n in ids.get(tok[1], ()):
                    out[n].append((t, tok[0][1:]))
            elif c in "01xXzZ":
                for n in ids.get(tok[0][1:], ()):
                    out[n].append((t, c))
    return out, times


def _value(bits: str, fmt: str) -> str:
    if any(b not in "01" for b in bits):
        return "x"
    return format(int(bits, 2), fmt)


def wave_svg(vcd: Path, out: Path, *, title: str = "", max_edges: int = 40) -> Path | None:
    """Write ``out`` (SVG) with the trace's clock, cycle counter and stream ports over its first
    ``max_edges`` rising clock edges; None (nothing written) when the trace has no clock."""
    vars_ = waves.vcd_header(vcd)
    top, ports = waves.stream_signals(vars_)
    clk = waves._shallowest(vars_, "clk", top[:-1])
    if clk is None:
        return None
    cycle = next((f"rasterhw.cycle{r}" for s, n, w, r, i in vars_ if s == ("rasterhw",) and n == "cycle"), None)
    rows = [clk, *([cycle] if cycle else []), *[n for names in ports.values() for n in names
                                                  if "__payload." not in n]]
    strip = {n: n.rsplit("[", 1)[0] if n.endswith("]") else n for n in rows}   # GTKWave name -> VCD name
    vals, _times = _changes(vcd, {n: strip[n] for n in rows})
    edges = [t for t, v in vals[clk] if v == "1"][: max_edges + 1]
    if len(edges) < 2:
        return None
    t0, t1 = edges[0], edges[-1]
    x = lambda t: _NAME_W + (t - t0) / (t1 - t0) * _STEP_W * (len(edges) - 1)   # noqa: E731
    width = int(_NAME_W + _STEP_W * (len(edges) - 1) + 10)
    height = _ROW * (len(rows) + 1) + 10
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="monospace" font-size="11">',
           f'<text x="4" y="14" font-weight="bold">{escape(title)}</text>']
    for k, n in enumerate(rows):
        y = _ROW * (k + 1) + 6
        svg.append(f'<text x="4" y="{y + 13}">{escape(n.split(".", len(top))[-1] if top else n)}</text>')
        seq = vals[n]
        cur = next((v for t, v in reversed(seq) if t <= t0), seq[0][1] if seq else "x")
        pts = [(t0, cur)] + [(t, v) for t, v in seq if t0 < t <= t1] + [(t1, None)]
        one_bit = all(len(v) == 1 for _, v in pts if v is not None)
        for (ta, va), (tb, _) in zip(pts, pts[1:], strict=False):
            xa, xb = x(ta), x(tb)
            if one_bit:
                yy = y + (3 if va == "1" else 17)
                svg.append(f'<line x1="{xa:.1f}" y1="{yy}" x2="{xb:.1f}" y2="{yy}" stroke="#2a6"/>')
                if tb != t1:
                    svg.append(f'<line x1="{xb:.1f}" y1="{y + 3}" x2="{xb:.1f}" y2="{y + 17}" stroke="#2a6"/>')
            else:
                svg.append(f'<polygon points="{xa + 2:.1f},{y + 10} {xa + 4:.1f},{y + 3} {xb - 2:.1f},{y + 3} '
                           f'{xb:.1f},{y + 10} {xb - 2:.1f},{y + 17} {xa + 4:.1f},{y + 17}" fill="none" stroke="#36a"/>')
                label = _value(va, "d" if n.split("[")[0].endswith("cycle") else "x")   # the counter in decimal
                if (xb - xa) > 6 * len(label) + 4:
                    svg.append(f'<text x="{xa + 5:.1f}" y="{y + 14}" font-size="9">{label}</text>')
    svg.append("</svg>")
    out.write_text("\n".join(svg) + "\n")
    return out
