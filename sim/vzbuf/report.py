"""Report rows of the vector Z-buffer machine: tables 1-7 and fig. 3, ours beside the paper's.

``rasterhw report vzbuf`` (or ``python -m rasterhw.sim.vzbuf.report``) runs every scene with
both algorithms and all three shadow settings, recording the paper's loops as they run
(:mod:`~rasterhw.golden_model.vzbuf.trace`), and prices the trace on the scalar unit, the VP100
and the VP200 (:mod:`~rasterhw.golden_model.vzbuf.facom`): rows ``model:scalar``,
``model:vp100``, ``model:vp200`` beside the paper's ms, the ratios the paper concludes from, the
conclusions (a)-(e) and a sensitivity row per chosen parameter. NumPy wall times are not report
rows (they would change every run): ``rasterhw bench vzbuf`` measures them.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.golden_model.reference import rasterise
from rasterhw.golden_model.scenes import build_scene as _shared_scene
from rasterhw.golden_model.vzbuf.facom import LINEAR, PARAMS, bounds, length10_ratio, price
from rasterhw.golden_model.vzbuf.paper import (
    COLS,
    COLUMN,
    CORRECTED,
    RATES,
    RUNS,
    SLIST_SPEEDUP_AT_MOST,
    SP8_EMPTY_LINE_FRACTION,
    T1,
    TABLES,
    VTIME,
)
from rasterhw.golden_model.vzbuf.render import render_frame, table_stages
from rasterhw.golden_model.vzbuf.shadows import ray_shadow
from rasterhw.golden_model.vzbuf.stats import table1
from rasterhw.golden_model.vzbuf.trace import Trace
from rasterhw.golden_model.vzbuf.workload import table1_light
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import make_row
from rasterhw.sim.vzbuf.calibrate import (
    FIT_TABLE,
    error_factors,
    fit,
    predict,
    stage_components,
    summary,
)

SYS = "vzbuf"
W = H = 512

T1_KEYS = ("initial polygons", "initial shadow polygons", "processed polygons", "processed shadow polygons",
           "segments", "shadow segments", "pixels processed", "shadow pixels processed", "area per polygon",
           "shadow area per polygon")


def build_scene(name: str):
    """A paper scene under vzbuf's table-1 light (``workload.py``): every report run uses it."""
    return table1_light(_shared_scene(name))


def _say(progress, msg):
    if progress:
        print(msg, file=sys.stderr, flush=True)


def _f(v, nd=1):
    return "—" if v is None else (f"{v:,.{nd}f}" if isinstance(v, float) else f"{v:,}")


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path = Path("docs/reproduction"),
         scenes=COLS, **known) -> tuple[list[dict], list[str]]:
    """Every row (see the module docstring); ``scenes`` narrows the run (tests)."""
    out: list[dict] = []
    sec: list[str] = []
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)

    # ------------------------------------------------------------------ table 1
    t1 = {}
    for n in scenes:
        _say(progress, f"vzbuf: table 1, {n}")
        t1[n] = table1(build_scene(n), W, H)
        for k in T1_KEYS:
            if k in t1[n]:
                out.append(make_row(SYS, "table 1", f"{n}: {k}", paper=T1[k][n], formula=None,
                                    measured=t1[n][k], unit="px" if "pixels" in k or "area" in k else "count",
                                    source="golden"))
        for k in ("mean length x", "mean length y", "shadow mean length x", "shadow mean length y"):
            if k in t1[n]:
                out.append(make_row(SYS, "table 1", f"{n}: {k} (paper's rows unassignable)", paper=None,
                                    formula=None, measured=t1[n][k], unit="px", source="golden"))
        out.append(make_row(SYS, "table 1", f"{n}: segments per processed polygon",
                            paper=T1["segments"][n] / T1["processed polygons"][n], formula=None,
                            measured=t1[n]["segments"] / t1[n]["processed polygons"], unit="ratio",
                            source="golden"))
        out.append(make_row(SYS, "table 1 note", f"{n}: empty scan lines", paper=SP8_EMPTY_LINE_FRACTION * H if n == "sp8" else None,
                            formula=None, measured=t1[n]["empty lines"], unit="lines", source="golden"))
        # the same shadow rows under the scene's own light: what the table-1 light changed (workload.py)
        own = table1(_shared_scene(n), W, H)
        for k in ("initial shadow polygons", "shadow area per polygon"):
            if k in own:
                out.append(make_row(SYS, "table 1", f"{n}: {k} (the scene's own light, not used)", paper=T1[k][n],
                                    formula=None, measured=own[k], unit="px" if "area" in k else "count",
                                    source="golden"))
    cubes = [n for n in scenes if n.startswith("c")]
    if len(cubes) >= 2:
        nn = np.array([int(n[1:]) for n in cubes], float)
        for key in ("pixels processed", "shadow pixels processed", "segments"):
            ours = np.polyfit(nn, [t1[n][key] for n in cubes], 1)[0]
            pap = np.polyfit(nn, [T1[key][n] for n in cubes], 1)[0]
            out.append(make_row(SYS, "table 1", f"growth per cube: {key} (least squares over {', '.join(cubes)})",
                                paper=float(pap), formula=None, measured=float(ours), unit="per cube",
                                source="golden"))

    # ------------------------------------------------------------------ correctness
    for n in scenes:
        sc = build_scene(n)
        for alg in (1, 2):
            f = render_frame(sc, W, H, alg=alg)
            ref = rasterise(f.sp.tris)
            differ = f.poly != ref.poly_id
            ties = differ & (f.depth == ref.depth)
            m = f.poly >= 0
            rel = float((np.abs(f.depth[m] - ref.depth[m]) / np.abs(ref.depth[m])).max()) if m.any() else 0.0
            di = float(np.abs(f.inten[m] - ref.colour[..., 0][m]).max()) if m.any() else 0.0
            out.append(make_row(SYS, "check", f"{n}: vz{alg} pixels whose visible polygon differs from the reference",
                                paper=None, formula=None, measured=int(differ.sum()), unit="px", source="golden"))
            out.append(make_row(SYS, "check", f"{n}: vz{alg} of them exact-z ties", paper=None, formula=None,
                                measured=int(ties.sum()), unit="px", source="golden"))
            out.append(make_row(SYS, "check", f"{n}: vz{alg} largest relative depth difference", paper=None,
                                formula=None, measured=rel, unit="relative", source="golden"))
            out.append(make_row(SYS, "check", f"{n}: vz{alg} largest |I - I_ref| (scan-line Gouraud on quads)",
                                paper=None, formula=None, measured=di, unit="intensity", source="golden"))

    # ------------------------------------------------------------------ timing tables 2-7 (model)
    times = {}
    comps = {}
    for table, (alg, sh) in RUNS.items():
        T = TABLES[table]
        for n in scenes:
            sc = build_scene(n)
            tr = Trace()
            try:
                f = render_frame(sc, W, H, alg=alg, shadows=sh, trace=tr)
            except RasterhwError as e:  # a scene without ground cannot have shadow polygons
                _say(progress, f"vzbuf: {table} {n}: {e}")
                continue
            _say(progress, f"vzbuf: {table} {n}: traced {len(tr.loops)} loop shapes")
            labels = {k.split()[0]: k for k in table_stages(alg, sh)}
            ms = model_ms(tr, alg, sh)
            times[(table, n)] = (ms, f, tr)
            comps[(table, n)] = stage_components(tr, alg, sh)
            for stage in (*labels, "total"):
                for m in MODELS:
                    pm = COLUMN[m]
                    pv = T[pm][stage][n] if pm in T else None
                    out.append(make_row(SYS, table, f"{n}: {labels.get(stage, 'total')}", paper=pv, formula=None,
                                        measured=ms[m][stage], unit="ms", source=f"model:{m}"))
            for m in ("vp100", "vp200"):
                pm = COLUMN[m]
                pg = (T["scalar"]["total"][n] / T[pm]["total"][n]
                      if pm in T and T[pm]["total"][n] and T["scalar"]["total"][n] else None)
                out.append(make_row(SYS, table, f"{n}: vectorisation gain, scalar / {pm} total", paper=pg,
                                    formula=None, measured=ms["scalar"]["total"] / ms[m]["total"], unit="ratio",
                                    source=f"model:{m}"))
            if "VP100" in T:
                for stage in ("2", "total"):
                    p1, p2 = T["VP100"][stage][n], T["VP200"][stage][n]
                    out.append(make_row(SYS, table, f"{n}: VP100 / VP200 time, {labels.get(stage, 'total')}",
                                        paper=p1 / p2 if p1 and p2 else None, formula=None,
                                        measured=ms["vp100"][stage] / ms["vp200"][stage], unit="ratio",
                                        source="model:facom"))
            for m in ("vp100", "vp200"):
                out.append(make_row(SYS, table, f"{n}: vector time (vector unit in use), {COLUMN[m]}",
                                    paper=VTIME[table][COLUMN[m]][n] if table in VTIME else None, formula=None,
                                    measured=ms[m]["vector"], unit="ms", source=f"model:{m}"))
            if table in RATES:
                for m in ("vp100", "vp200"):
                    out.append(make_row(SYS, table, f"{n}: vectorisation rate (4), {COLUMN[m]}",
                                        paper=RATES[table][COLUMN[m]][n], formula=None, measured=ms[m]["rate"],
                                        unit="%", source=f"model:{m}"))
            if sh != "map":
                vp = T["VP200"]["total"][n]
                px = f.stats["pixels_real"] + f.stats["pixels_shadow"]
                pap_px = T1["pixels processed"][n] + (T1["shadow pixels processed"][n] if sh == "polygons" else 0)
                out.append(make_row(SYS, table, f"{n}: pixels (real{' + shadow' if sh == 'polygons' else ''}) per second",
                                    paper=pap_px / (vp / 1e3) if vp else None, formula=None,
                                    measured=px / (ms["vp200"]["total"] / 1e3), unit="px/s", source="model:vp200"))

    # ------------------------------------------------------------------ claims, conclusions, fig. 3
    def claim(fig, q, paper, measured, unit="ratio", source="model:vp200"):
        out.append(make_row(SYS, fig, q, paper=paper, formula=None, measured=measured, unit=unit, source=source))

    def tot(table, n, m="vp200", stage="total"):
        return times[(table, n)][0][m][stage] if (table, n) in times else None

    for n in scenes:
        if tot("table 2", n) and tot("table 3", n):
            for m in ("vp100", "vp200"):
                p2, p3 = TABLES["table 2"][COLUMN[m]]["total"][n], TABLES["table 3"][COLUMN[m]]["total"][n]
                claim("text 3.3 1)", f"{n}: algorithm 1 total / algorithm 2 total, no shadows, {COLUMN[m]}",
                      p2 / p3 if p2 and p3 else None, tot("table 2", n, m) / tot("table 3", n, m), source=f"model:{m}")
    model_get = _getter_model(times)
    res = conclusions(model_get, scenes)
    pres = conclusions(_getter_paper(), scenes)
    for key, (frac, what) in res.items():
        claim("conclusions", f"{_cname(key)} {what}: fraction of cases that hold (1 = holds)", pres[key][0], frac,
              unit="fraction", source=CONCLUSION_SOURCE[key])
    if tot("table 3", "c300"):
        claim("conclusions", "(e) table 3, c300, VP200 total: model / paper", 1.0, tot("table 3", "c300") / TABLES["table 3"]["VP200"]["total"]["c300"],
              source="model:vp200")
    # the published facts the parameters are bounded by (facom.bounds; not the paper's)
    for m in ("vp200", "vp100"):
        claim("published bounds", f"{COLUMN[m]} / X-MP time of V = S x V + V at vector length 10 (Lubeck, Moore, "
              "Mendez: the VP-200 and the X-MP 'performed equally on short vectors (vector length 10)'; "
              "bound for the VP-200 1/1.3-1.3)", None, length10_ratio(machine=m), source=f"model:{m}")
    # sensitivity: every chosen parameter at half and double, the conclusions recomputed
    kept = {k: v for k, v in times.items() if k[0] in ("table 2", "table 3")}
    for pname, par in PARAMS.items():
        if not par.chosen:
            continue
        for fac in (0.5, 2.0):
            val = par.value * fac
            alt = {k: (model_ms(tr, *RUNS[k[0]], params={pname: val}), f, tr) for k, (_, f, tr) in kept.items()}
            r = conclusions(_getter_model(alt), scenes)
            for key, (frac, _what) in r.items():
                if key not in SENSITIVITY_KEYS:
                    continue
                claim("sensitivity", f"{pname} x{fac:g} (= {val:g} {par.unit}): {_sname(key)}, fraction holding",
                      None, frac, unit="fraction", source=CONCLUSION_SOURCE[key])
    if ("table 5", "c300") in times and ("table 4", "c300") in times:
        c1 = _parts(times[("table 4", "c300")][2])
        c2 = _parts(times[("table 5", "c300")][2])
        claim("fig. 3", "c300, shadow polygons: hidden-surface (Z-test) speed, algorithm 2 / algorithm 1",
              2.4, c1["Z-test"] / c2["Z-test"])
        claim("fig. 3", "c300, shadow polygons: update speed, algorithm 2 / algorithm 1", 0.5,
              (c1["update 1"] + c1["update 2"]) / (c2["update 1"] + c2["update 2"]))
        _fig3(out_dir, c1, c2)
        sec.append("## Fig. 3: c300 with shadow polygons, hidden-surface step by part (model, VP200)\n\n"
                   "![fig. 3](vzbuf_fig3.png)\n\nZ-test = span set-up and Z tests; update 1 = edge steps; "
                   "update 2 = segments entering and leaving (x-list / s-list). The paper's bars are lost in "
                   "the OCR; its text gives the ratios 2.4 and about 0.5 (rows above).\n")
    for n in ("c300", "c50"):
        if ("table 5", n) in times:
            ms, f, _ = times[("table 5", n)]
            claim("text 4.2 1)", f"{n}: shadow stage per million shadow pixels (table 5, VP200)",
                  TABLES["table 5"]["VP200"]["3"][n] / (T1["shadow pixels processed"][n] / 1e6),
                  ms["vp200"]["3"] / (f.stats["pixels_shadow"] / 1e6), unit="ms/Mpx")
    for n in ("c300", "sp8"):
        if ("table 6", n) in times and ("table 2", n) in times:
            claim("text 3.3 3)", f"{n}: algorithm 1 with a full-frame Z-buffer (table 6 stage 1) / table 2 total",
                  TABLES["table 6"]["VP200"]["1"][n] / TABLES["table 2"]["VP200"]["total"][n],
                  tot("table 6", n, stage="1") / tot("table 2", n))
        if ("table 7", n) in times and ("table 3", n) in times:
            claim("text 4.2 2)", f"{n}: ray casting's two hidden-surface stages / no-shadow total (algorithm 2)",
                  (TABLES["table 7"]["VP200"]["1"][n] + TABLES["table 7"]["VP200"]["2"][n])
                  / TABLES["table 3"]["VP200"]["total"][n],
                  (tot("table 7", n, stage="1") + tot("table 7", n, stage="2")) / tot("table 3", n))

    out.extend(where_the_time_goes(times, t1))
    out.extend(agreement_rows(times, scenes))
    out.extend(calibration_rows(comps, scenes))

    # ------------------------------------------------------------------ shadows vs brute force
    for n in scenes:
        if ("table 5", n) not in times or ("table 7", n) not in times:
            continue
        sc = build_scene(n)
        fp = times[("table 5", n)][1]
        fm = times[("table 7", n)][1]
        ray = ray_shadow(sc, W, H, fp.depth, fp.poly)
        vis = fp.poly >= 0
        out.append(make_row(SYS, "check", f"{n}: shadow polygons agree with the ray to the light", paper=None,
                            formula=None, measured=float((ray == fp.shadowed)[vis].mean()), unit="fraction",
                            source="golden"))
        out.append(make_row(SYS, "check", f"{n}: shadow map agrees with the ray to the light", paper=None,
                            formula=None, measured=float((ray == fm.shadowed)[vis].mean()), unit="fraction",
                            source="golden"))
        out.append(make_row(SYS, "check", f"{n}: shadow map vs shadow polygons, differing visible pixels",
                            paper=None, formula=None, measured=int((fm.shadowed != fp.shadowed)[vis].sum()),
                            unit="px", source="golden"))
        out.append(make_row(SYS, "check", f"{n}: visible pixels in shadow (shadow polygons)", paper=None,
                            formula=None, measured=int(fp.shadowed.sum()), unit="px", source="golden"))

    # shadow-map epsilon: the paper gives none; agreement with the ray check over a sweep
    if "c300" in scenes and ("table 5", "c300") in times:
        sc = build_scene("c300")
        fp = times[("table 5", "c300")][1]
        ray = ray_shadow(sc, W, H, fp.depth, fp.poly)
        vis = fp.poly >= 0
        for eps in (1e-3, 2e-3, 5e-3, 1e-2, 2e-2):
            fm = render_frame(sc, W, H, alg=2, shadows="map", eps=eps)
            out.append(make_row(SYS, "check", f"c300: shadow map (eps = {eps:g}) agrees with the ray to the light",
                                paper=None, formula=None, measured=float((ray == fm.shadowed)[vis].mean()),
                                unit="fraction", source="golden"))

    # vector lengths
    for n in scenes:
        for table in ("table 2", "table 3"):
            if (table, n) in times:
                c = times[(table, n)][1].stats["counters"]
                alg = RUNS[table][0]
                out.append(make_row(SYS, table, f"{n}: algorithm {alg} mean Z-test vector length", paper=None,
                                    formula=None, measured=c["mean_vector_length"], unit="elements", source="golden"))
                out.append(make_row(SYS, table, f"{n}: algorithm {alg} passes ({'lines' if alg == 1 else 'loop iterations'})",
                                    paper=None, formula=None, measured=c["passes"], unit="count", source="golden"))
                tr = times[(table, n)][2]
                out.append(make_row(SYS, table, f"{n}: algorithm {alg} mean Z-test loop length in the trace "
                                    f"({'span' if alg == 1 else 'occupied slots, masked'})", paper=None, formula=None,
                                    measured=tr.mean_length(f"a{alg} z-test real"), unit="elements", source="golden"))

    sec += _sections(t1, times, scenes)
    if times:
        _plot_tables(out_dir, times, scenes)
        sec.append("## Tables 2-7: totals, the model beside the paper's\n\n![tables](vzbuf_tables.png)\n")
    return out, sec


MODELS = ("scalar", "vp100", "vp200")
CUBES = ("c300", "c250", "c200", "c150", "c100", "c50")


def model_ms(tr: Trace, alg: int, sh: str, params: dict | None = None) -> dict:
    """ms per table stage ("1", "2", ..., "total") on each machine, and the vectorisation rate
    (4) in % on the VPs: scalar time of the part each VP vectorises / total scalar time."""
    st = table_stages(alg, sh)
    out = {}
    for m in MODELS:
        r = price(tr, m, params=params)
        ph = r["phases"]
        d = {k.split()[0]: 1e3 * sum(ph.get(p, 0.0) for p in v) for k, v in st.items()}
        d["total"] = sum(d.values())
        out[m] = d
        if m != "scalar":
            d["rate"] = 100.0 * 1e3 * sum(r["vectorised_scalar"].values()) / out["scalar"]["total"]
            d["vector"] = 1e3 * sum(r["vector"].values())
    return out


FIG_E = "where the time goes (e)"


def where_the_time_goes(times, t1, n: str = "c300") -> list[dict]:
    """Conclusion (e)'s gap on c300 taken apart with no parameter changed: the unit price of the
    simplest loop (buffer initialisation, a store per element) beside the paper's, a fixed
    floating-point loop body (eye -> light transform) relative to it, the work per item of the
    stages the model prices lightest, the time outside the vector unit, and two speed-ups the
    paper's text states (docs/vzbuf.md, conclusion (e))."""
    out: list[dict] = []

    def row(q, paper, measured, unit, source):
        out.append(make_row(SYS, FIG_E, f"{n}: {q}", paper=paper, formula=None, measured=measured, unit=unit,
                            source=source))

    def ms(table, m, stage="total"):
        return times[(table, n)][0][m][stage]

    T = TABLES
    if ("table 6", n) in times:
        elems = 3 * W * H     # image memory, Z-buffer, shadow buffer ("画像記憶・Zバッファ・影バッファの初期化")
        for m in ("scalar", "vp200"):
            pm = COLUMN[m]
            row(f"buffer initialisation, ns per buffer element ({pm}; table 6 stage 4 / 3 x 512^2)",
                T["table 6"][pm]["4"][n] * 1e6 / elems, ms("table 6", m, "4") * 1e6 / elems, "ns", f"model:{m}")
            row(f"eye->light transform / buffer initialisation ({pm}; table 6 stage 3 / stage 4)",
                T["table 6"][pm]["3"][n] / T["table 6"][pm]["4"][n], ms("table 6", m, "3") / ms("table 6", m, "4"),
                "ratio", f"model:{m}")
    if ("table 3", n) in times and n in t1:
        npoly = t1[n]["initial polygons"]
        row("set-up, scalar time per initial polygon (table 3 stage 1)", T["table 3"]["scalar"]["1"][n] * 1e3 / npoly,
            ms("table 3", "scalar", "1") * 1e3 / npoly, "us", "model:scalar")
        row("algorithm 2 hidden-surface removal, scalar time per pixel processed (table 3 stage 2 / table 1 pixels)",
            T["table 3"]["scalar"]["2"][n] * 1e3 / T1["pixels processed"][n],
            ms("table 3", "scalar", "2") * 1e3 / t1[n]["pixels processed"], "us", "model:scalar")
    if ("table 2", n) in times and n in t1:
        row("segment build, scalar time per segment (table 2 stage 3 / table 1 segments)",
            T["table 2"]["scalar"]["3"][n] * 1e3 / T1["segments"][n],
            ms("table 2", "scalar", "3") * 1e3 / t1[n]["segments"], "us", "model:scalar")
        # 4.1 1)(i): "ベクトル化による隠れ面消去処理の処理速度の向上率は約1.5~2倍"
        for m in ("vp100", "vp200"):
            pm = COLUMN[m]
            row(f"algorithm 1 hidden-surface removal, scalar / {pm} (text 4.1 1)(i): about 1.5-2)",
                T["table 2"]["scalar"]["2"][n] / T["table 2"][pm]["2"][n],
                ms("table 2", "scalar", "2") / ms("table 2", m, "2"), "ratio", f"model:{m}")
    for table in ("table 2", "table 3"):
        if (table, n) not in times:
            continue
        for m in ("vp100", "vp200"):
            pm = COLUMN[m]
            row(f"{table}: time outside the vector unit, {pm} (total - vector time)",
                T[table][pm]["total"][n] - VTIME[table][pm][n],
                ms(table, m) - times[(table, n)][0][m]["vector"], "ms", f"model:{m}")
    if ("table 3", n) in times:
        # 4.1 2)(ii) 2: "slistの更新処理はベクトル化されるが…処理速度の向上は高々4倍にとどまる"
        tr = times[("table 3", n)][2]
        sc = price(tr, "scalar", by="body")["phases"]
        for m in ("vp100", "vp200"):
            vp = price(tr, m, by="body")["phases"]
            row(f"s-list shift slist(i+1) <- slist(i), scalar / {COLUMN[m]} (text 4.1 2)(ii): at most 4)", SLIST_SPEEDUP_AT_MOST,
                sc["a2 shift s-list"] / vp["a2 shift s-list"], "ratio", f"model:{m}")
    return out


def _getter_model(times):
    def get(table, n, m, stage="total"):
        return times[(table, n)][0][m][stage] if (table, n) in times else None
    return get


def _getter_paper():
    def get(table, n, m, stage="total"):
        T = TABLES[table]
        pm = COLUMN[m]
        return T[pm][stage][n] if pm in T else None
    return get


def conclusions(get, scenes) -> dict:
    """The issue's checks (a)-(e) on tables 2 and 3, from ``get(table, scene, machine, stage)``:
    each -> (fraction of its cases that hold, what it says); cases with a missing value skipped.
    Keys ``a`` ... ``e`` are the combined checks; ``a vp100`` ... ``b vp200`` the same per machine,
    ``c first half`` / ``c second half`` the two halves of (c) (:data:`CONCLUSION_SOURCE` says
    which model each reads)."""
    def frac(cases):
        cases = [c for c in cases if c is not None]
        return (sum(cases) / len(cases)) if cases else float("nan")

    def gain(table, n, m):
        s, v = get(table, n, "scalar"), get(table, n, m)
        return s / v if s and v else None

    both = [n for n in scenes if get("table 2", n, "vp200") and get("table 3", n, "vp200")]
    a = {"vp100": [], "vp200": []}
    b = {"vp100": [], "vp200": []}
    c1, c2 = [], []
    for n in both:
        for m in ("vp100", "vp200"):
            g1, g2 = gain("table 2", n, m), gain("table 3", n, m)
            a[m].append(None if g1 is None or g2 is None else g2 > g1)
            b[m].append(None if g1 is None else 1.5 <= g1 <= 5)
            b[m].append(None if g2 is None else 4 <= g2 <= 12)
    for n in (x for x in both if x in CUBES):
        h1, h2 = get("table 2", n, "vp100", "2"), get("table 2", n, "vp200", "2")
        c1.append(None if not (h1 and h2) else h2 >= 0.9 * h1)
        h1, h2 = get("table 3", n, "vp100", "2"), get("table 3", n, "vp200", "2")
        c2.append(None if not (h1 and h2) else h1 / h2 > 1.2)
    d = []
    for n, want in (("c300", True), ("sp8", False)):
        t1, t2 = get("table 2", n, "vp200"), get("table 3", n, "vp200")
        d.append(None if not (t1 and t2) else (t2 < t1) == want)
    t = get("table 3", "c300", "vp200")
    e = [None if not t else 0.5 <= t / 293.0 <= 2.0]
    return {"a": (frac(a["vp100"] + a["vp200"]),
                  "algorithm 2's vectorisation gain > algorithm 1's, every scene, VP100 and VP200"),
            "a vp100": (frac(a["vp100"]), "algorithm 2's vectorisation gain > algorithm 1's, every scene"),
            "a vp200": (frac(a["vp200"]), "algorithm 2's vectorisation gain > algorithm 1's, every scene"),
            "b": (frac(b["vp100"] + b["vp200"]), "gains within 1.5-5 (algorithm 1) and 4-12 (algorithm 2)"),
            "b vp100": (frac(b["vp100"]), "gains within 1.5-5 (algorithm 1) and 4-12 (algorithm 2)"),
            "b vp200": (frac(b["vp200"]), "gains within 1.5-5 (algorithm 1) and 4-12 (algorithm 2)"),
            "c": (frac(c1 + c2), "cubes: alg. 1 hidden-surface VP200 >= 0.9 x VP100, alg. 2 VP100/VP200 > 1.2"),
            "c first half": (frac(c1), "cubes: algorithm 1's hidden-surface time on the VP200 >= 0.9 x the VP100's "
                             "(table 2 stage 2; 4.1 1)(ii): 'ハードウェア量が2倍に増えても、処理時間の改善はあまり"
                             "なかった')"),
            "c second half": (frac(c2), "cubes: algorithm 2's hidden-surface time VP100 / VP200 > 1.2 (table 3 stage "
                              "2; 4.1 2)(ii): '処理速度も1.5~1.9倍になっている')"),
            "d": (frac(d), "VP200: algorithm 2 total below algorithm 1's on c300, above on sp8"),
            "e": (frac(e), "table 3 c300 VP200 total within 0.5-2 x the paper's 293 ms")}


#: which model each conclusion row reads (the machines its cases compare)
CONCLUSION_SOURCE = {"a": "model:vp100|vp200", "a vp100": "model:vp100", "a vp200": "model:vp200",
                     "b": "model:vp100|vp200", "b vp100": "model:vp100", "b vp200": "model:vp200",
                     "c": "model:vp100|vp200", "c first half": "model:vp100|vp200",
                     "c second half": "model:vp100|vp200", "d": "model:vp200", "e": "model:vp200"}
#: the conclusions each sensitivity run recomputes
SENSITIVITY_KEYS = ("a", "b", "c", "c first half", "c second half", "d", "e")


def _cname(key: str) -> str:
    """``a`` -> ``(a)``; ``c first half`` -> ``conclusion (c), first half:``; ``a vp100`` ->
    ``conclusion (a), VP100:``."""
    if " " not in key:
        return f"({key})"
    k, rest = key.split(" ", 1)
    return f"conclusion ({k}), {COLUMN.get(rest, rest)}:"


def _sname(key: str) -> str:
    """The sensitivity rows' name of a conclusion: ``conclusion (a)``, ``conclusion (c), first half``."""
    return f"conclusion ({key})" if " " not in key else _cname(key)[:-1]


def _gmean(xs) -> float | None:
    xs = [x for x in xs if x and x > 0]
    return float(np.exp(np.mean(np.log(xs)))) if xs else None


def agreement_rows(times, scenes) -> list[dict]:
    """Per table and machine, the uncalibrated model's geometric mean of model / paper over every
    stage and total cell, and the median error factor max(r, 1/r) over all machines."""
    out = []
    for table in TABLES:
        T = TABLES[table]
        allf = []
        for m in MODELS:
            pm = COLUMN[m]
            if pm not in T:
                continue
            r = []
            for n in scenes:
                if (table, n) not in times:
                    continue
                ms = times[(table, n)][0][m]
                for st in T[pm]:
                    pv = T[pm][st].get(n)
                    if pv and st in ms:
                        r.append(ms[st] / pv)
            if not r:
                continue
            allf += [max(x, 1 / x) for x in r]
            out.append(make_row(SYS, table, f"geometric mean model / paper, {pm} (every stage and total, "
                                "uncalibrated model)", paper=1.0, formula=None, measured=_gmean(r), unit="ratio",
                                source=f"model:{m}"))
        if allf:
            out.append(make_row(SYS, table, "uncalibrated model error max(model / paper, paper / model): median "
                                "factor (every stage and total, every machine)", paper=1.0, formula=None,
                                measured=float(np.median(allf)), unit="factor", source="model:scalar|vp100|vp200"))
    return out


def calibration_rows(comps, scenes) -> list[dict]:
    """The table-2 calibration (sim/vzbuf/calibrate.py): the fitted values beside their bounds,
    every stage and total of tables 2-7 at those values beside the paper's, and the error of the
    fit in sample (table 2) and out of sample (tables 3-7). Never read by the conclusions."""
    out = []
    if not any(k[0] == FIT_TABLE for k in comps):
        return out
    start = {k: PARAMS[k].value for k in LINEAR}
    theta = fit(comps, TABLES, start)
    b = bounds()
    for p in LINEAR:
        lo, hi, why = b.get(p, (None, None, "chosen"))
        where = f"bounds {lo:.4g}-{hi:.4g} {PARAMS[p].unit}, {why.split(':')[0].split(' (')[0]}" if lo is not None \
            else "no bounds"
        out.append(make_row(SYS, "calibration", f"fitted {p} on {FIT_TABLE} ({where}; the model's value "
                            f"{PARAMS[p].value:g})", paper=None, formula=None, measured=theta[p],
                            unit=PARAMS[p].unit, source="fit:table2"))
        if lo is not None:
            out.append(make_row(SYS, "calibration", f"fitted {p}: inside its bounds (1 = yes)", paper=None,
                                formula=None, measured=int(lo <= theta[p] <= hi), unit="flag", source="fit:table2"))
    pred = {k: predict(c, theta) for k, c in comps.items()}
    for table in TABLES:
        T = TABLES[table]
        alg, sh = RUNS[table]
        labels = {k.split()[0]: k for k in table_stages(alg, sh)}
        for n in scenes:
            if (table, n) not in pred:
                continue
            for m in MODELS:
                pm = COLUMN[m]
                for stage in (*labels, "total"):
                    pv = T[pm][stage][n] if pm in T else None
                    out.append(make_row(SYS, table, f"{n}: {labels.get(stage, 'total')}, {pm} (calibrated on "
                                        f"{FIT_TABLE})", paper=pv, formula=None, measured=pred[(table, n)][m][stage],
                                        unit="ms", source="fit:table2"))
        med, gm = summary(error_factors(pred, TABLES, table))
        which = "in-sample" if table == FIT_TABLE else "out-of-sample"
        for what, v in (("median factor", med), ("geometric mean factor", gm)):
            out.append(make_row(SYS, table, f"{which} error of the {FIT_TABLE} calibration, max(fit / paper, "
                                f"paper / fit) over every stage and total: {what}", paper=1.0, formula=None,
                                measured=v, unit="factor", source="fit:table2"))
    return out


_Z = ("a1 z-test real", "a1 z-test shadow", "a2 z-test real", "a2 z-test shadow", "a1 span set-up", "a2 span set-up",
      "span loop set-up", "z-test step", "line set-up")
_U1 = ("edge update",)
_U2 = ("a1 drop exited", "a2 drop exited", "a2 take y-list head", "a2 collect slots", "a2 shift s-list",
       "x-list append", "pass control", "line loop")


def _parts(tr: Trace, machine: str = "vp200") -> dict:
    """Fig. 3's parts of the hidden-surface step, priced on ``machine`` (seconds)."""
    r = price(tr, machine, by="body")["phases"]
    return {name: sum(r.get(k, 0.0) for k in keys) for name, keys in (("Z-test", _Z), ("update 1", _U1),
                                                                        ("update 2", _U2))}


def _fig3(out_dir, s1, s2):
    parts = ("Z-test", "update 1", "update 2")
    names = ("Z-test", "update 1 (edges)", "update 2 (enter/exit)")
    v1 = [1e3 * s1[p] for p in parts]
    v2 = [1e3 * s2[p] for p in parts]
    with saved_figure(Path(out_dir) / "vzbuf_fig3.png", figsize=(6, 3.2)) as ax:
        x = np.arange(3)
        ax.bar(x - 0.2, v1, 0.4, label="algorithm 1")
        ax.bar(x + 0.2, v2, 0.4, label="algorithm 2")
        ax.set_xticks(x, names)
        ax.set_ylabel("ms (timing model, VP200)")
        ax.set_title("c300 with shadow polygons: hidden-surface step by part")
        ax.legend()


def _plot_tables(out_dir, times, scenes):
    with saved_figure(Path(out_dir) / "vzbuf_tables.png", figsize=(12, 6.5), dpi=100, nrows=2, ncols=3) as axes:
        for ax, table in zip(axes.ravel(), TABLES, strict=True):
            T = TABLES[table]
            x = np.arange(len(scenes))

            def get(m, T=T):
                return [T[m]["total"][n] if m in T and T[m]["total"][n] is not None else np.nan for n in scenes]

            def mod(m, table=table):
                return [times[(table, n)][0][m]["total"] if (table, n) in times else np.nan for n in scenes]

            for i, m in enumerate(MODELS):
                ax.semilogy(x, get(COLUMN[m]), "o--", color=f"C{i}", label=f"paper {COLUMN[m]}")
                ax.semilogy(x, mod(m), "s-", color=f"C{i}", label=f"model {COLUMN[m]}")
            ax.set_xticks(x, scenes, rotation=60, fontsize=7)
            ax.set_title(f"{table} ({'alg 1' if RUNS[table][0] == 1 else 'alg 2'}, {RUNS[table][1]})", fontsize=9)
            ax.set_ylabel("total ms")
        axes[0, 0].legend(fontsize=6)


def _sections(t1, times, scenes) -> list[str]:
    s = []
    head = "| quantity | " + " | ".join(scenes) + " |\n|---|" + "---|" * len(scenes) + "\n"
    body = ""
    for k in T1_KEYS:
        body += f"| {k}: paper | " + " | ".join(_f(T1[k][n]) for n in scenes) + " |\n"
        body += f"| {k}: ours | " + " | ".join(_f(t1[n].get(k)) for n in scenes) + " |\n"
    for k in ("mean length x", "mean length y", "empty lines"):
        body += f"| {k}: ours | " + " | ".join(_f(t1[n].get(k)) for n in scenes) + " |\n"
    s.append("## Table 1 side by side\n\n" + head + body + "\n"
             "Comparable on a re-created random scene: the counts fixed by the recipe (initial polygons), "
             "ratios (segments per polygon, area per polygon, shadow to real pixels), growth per cube, "
             "orderings between scenes, vector lengths. Not comparable: absolute totals (our cube sizes, "
             "camera and ground are our own reading). Every row is under vzbuf's table-1 light "
             "(golden_model/vzbuf/workload.py: cubes 15 deg from behind the eye, spheres 30 deg at 45 deg "
             "aside), chosen so that the shadow rows approach the paper's (within 25 % but on sp5); the "
             "rows marked 'the scene's own light' show the shadow work without it. Tables 2-7 below are the timing model "
             "(golden_model/vzbuf/facom.py) pricing the traced loops, not NumPy times.\n")
    if times:
        for table in TABLES:
            T = TABLES[table]
            rows_ = []
            for n in scenes:
                if (table, n) not in times:
                    continue
                ms = times[(table, n)][0]
                for st in ms["scalar"]:            # the stages and the total
                    cells = []
                    for m in MODELS:
                        pm = COLUMN[m]
                        cells += [_f(T[pm][st][n] if pm in T else None, 0), _f(ms[m][st], 1)]
                    rows_.append(f"| {n} | {st} | " + " | ".join(cells) + " |")
            s.append(f"## {table} ({'algorithm 1' if RUNS[table][0] == 1 else 'algorithm 2'}, shadows "
                     f"{RUNS[table][1]}), ms: paper beside the timing model\n\n| scene | stage | paper scalar | "
                     "model scalar | paper VP100 | model VP100 | paper VP200 | model VP200 |\n"
                     "|---|---|---|---|---|---|---|---|\n" + "\n".join(rows_) + "\n")
    s.append("## Cells corrected from the paper's identities\n\n" + "\n".join(
        f"- {t}, {r}, {c}: {why}" for (t, r, c), why in CORRECTED.items()) + "\n")
    return s


if __name__ == "__main__":  # pragma: no cover
    from rasterhw.sim.report.rows import run_report

    run_report("vzbuf", out_dir=Path("docs/reproduction"), progress=True)
