"""``rasterhw report sparse``: seed 002's S_k, figs. 3-6, from the formula and from measurement.

Every ``measured`` value is produced in this run:

* ``golden`` — the Monte-Carlo window counter (:mod:`rasterhw.golden_model.sparse.montecarlo`)
  or the recursive search (:mod:`rasterhw.golden_model.sparse.search`) ran;
* ``model`` — the paper's timing formulas (5)-(12) evaluated on window counts measured in this
  run (instead of formula (1)'s counts).

``samples`` (default 20 000) sets the Monte-Carlo sample count per point; the seed is fixed.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from rasterhw.golden_model.pipeline import run_geometry
from rasterhw.golden_model.reference import random_triangles
from rasterhw.golden_model.scenes import build_scene
from rasterhw.golden_model.sparse import cycles as cy
from rasterhw.golden_model.sparse import montecarlo as mc
from rasterhw.golden_model.sparse import theory as th
from rasterhw.golden_model.sparse.fixed import broadcast_records
from rasterhw.golden_model.sparse.paper import PAPER_LOAD_MAX, PAPER_S_K, PAPER_TESTS_PER_PRIMITIVE
from rasterhw.golden_model.sparse.search import sparse_render
from rasterhw.golden_model.sparse.stack import stack_processor
from rasterhw.golden_model.sparse.vpcycles import (
    HDL_FIFO_DEPTH,
    SHALLOW_FIFO_DEPTH,
    coupled_matrix_vp,
    vp_standalone,
    vp_streams,
)
from rasterhw.sim.report.plots import saved_figure
from rasterhw.sim.report.rows import make_row

SYSTEM = "sparse"
M_BITS = 10  # the paper's full raster: 2**10 x 2**10
KS = (1, 2, 3, 4)
SEED = 2002
#: Monte-Carlo samples of the large-S growth rows (S = 10^4, 10^5)
GROWTH_SAMPLES = 4000
#: areas at which the Monte-Carlo counts are measured for figs. 3, 5, 6
S_GRID = (0.1, 0.3, 1.0, 1.8, 3.0, 6.0, 10.0, 23.3, 40.0, 100.0, 157.0, 300.0, 1000.0)


def _counts(S: float, n: int, p: int, M: int, test: str = "exact", seed: int = SEED) -> mc.MCResult:
    poly, off = mc.rectangles(S, M, seed=seed)
    return mc.level_counts(poly, off, n, p, test=test)


def _fmt_ci(r: mc.MCResult, i: int) -> str:
    return f"{r.mean[i]:.4g} ± {r.half95[i]:.2g}"


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path = Path("docs/reproduction"),
         samples: int = 20000, scenes: tuple[str, ...] = ("c300", "sp27"), s_grid: tuple[float, ...] = S_GRID,
         coupled_size: int = 1 << M_BITS, coupled_matrices: tuple[str, ...] = ("2x2", "4x4", "8x8", "16x16"),
         load_triangles: int = 3000, coupled_vp_matrices: tuple[str, ...] = ("2x2", "4x4", "8x8"),
         stack_size: int = 512, coupled_scene: str = "c300",
         stack_scenes: tuple[str, ...] = ("c300", "sp27"), stack_sizes: tuple[int, ...] = (512, 1 << M_BITS),
         scheduler: str = "serial", store=None, fresh: bool = False, fast: bool = False, **known):
    """Rows and markdown sections of the sparse-raster report (see the module docstring). ``fast``:
    the 8x8 and 16x16 matrices at 1024² in HDL (:func:`_large_matrix_hdl_rows`, minutes of
    Verilator) stay unmeasured with their reason."""
    M = int(samples)
    S_GRID = tuple(s_grid)  # noqa: N806 (the module default, narrowed by tests)
    out: list[dict] = []
    sec: list[str] = []
    L = th.L_RECT_5_1

    def row(fig, qty, *, paper, formula, measured, unit, source):
        out.append(make_row(SYSTEM, fig, qty, paper=paper, formula=formula, measured=measured, unit=unit,
                            source=source))

    # ---------------------------------------------------------------- S_k (formula (4))
    sk_meas = {}
    for k, paper in zip(KS, PAPER_S_K, strict=True):
        f = th.s_k(k)
        s_ex = mc.s_k_measured(k, m=M_BITS, M=M, seed=SEED, test="exact")
        s_ed = mc.s_k_measured(k, m=M_BITS, M=M, seed=SEED, test="edges")
        sk_meas[k] = (s_ex, s_ed)
        row("text after (4)", f"S_{k}: area with w_n = 1, {1 << k}x{1 << k}, 5:1 rectangles, exact test "
            f"(MC {M}, 95 % [{s_ex[1]:.3g}, {s_ex[2]:.3g}])", paper=paper, formula=round(f, 4),
            measured=round(s_ex[0], 4), unit="px", source="golden")
        row("text after (4)", f"S_{k}, edges-only test (MC {M}, 95 % [{s_ed[1]:.3g}, {s_ed[2]:.3g}])",
            paper=paper, formula=round(f, 4), measured=round(s_ed[0], 4), unit="px", source="golden")

    # S_k at one fixed rotation: (1)'s perimeter term sqrt(a^2 + b^2) U / 2 is the exact mean
    # count's a H + b W for a square window at 45 degrees (its largest value), so (1) and the
    # paper's S_k are those of the rectangle at 45 degrees; uniform rotations count fewer windows
    sk_rot = {}
    for k in KS[1:]:
        for name, ang in (("45°", math.pi / 4), ("0°", 0.0)):
            s_r = mc.s_k_measured(k, m=M_BITS, M=M, seed=SEED, test="exact", rotation=ang)
            sk_rot[(k, name)] = s_r
            row("text after (4)", f"S_{k}, 5:1 rectangles all at {name} rotation, exact window test (MC {M}, 95 % "
                f"[{s_r[1]:.3g}, {s_r[2]:.3g}])", paper=PAPER_S_K[k - 1], formula=round(th.s_k(k), 4),
                measured=round(s_r[0], 4), unit="px", source="golden")

    # ---------------------------------------------------------------- Monte-Carlo counts, fig. 3
    mono = {}  # S -> counts of the monoprocessor on the full raster (for Q_a)
    spr = {k: {} for k in KS}
    for S in S_GRID:
        mono[S] = _counts(S, M_BITS, 1, M)
        for k in KS:
            spr[k][S] = _counts(S, M_BITS - k, 1 << k, M)
    worst = []
    table = ["| k | S | level i | formula (1) w_i | measured w_i (95 %) | gap (formula − measured) / formula |",
             "|---|---|---|---|---|---|"]
    for k in KS:
        n, p = M_BITS - k, 1 << k
        for S in S_GRID:
            r = spr[k][S]
            f = th.windows(S, n, p)
            ratio = r.mean[1:] / f[1:]
            worst.append((float(ratio.max()), k, S, int(ratio.argmax()) + 1))
            if S in (1.0, 23.3, 1000.0):
                for i in range(1, n + 1):
                    table.append(f"| {k} | {S:g} | {i} | {f[i]:.4g} | {_fmt_ci(r, i)} | {1 - ratio[i - 1]:+.3f} |")
    for k in KS:
        n, p = M_BITS - k, 1 << k
        S = 100.0
        r = _counts(S, n, p, M)
        f = th.windows(S, n, p)
        for i in range(1, n + 1):
            row("fig. 3 / (1)", f"w_{i}(S=100), {p}x{p}, 5:1 rectangles, exact test, MC {M} (±{r.half95[i]:.2g})",
                paper=None, formula=round(float(f[i]), 5), measured=round(float(r.mean[i]), 5), unit="windows",
                source="golden")
    wmax = max(worst)
    row("fig. 3 / (1)", f"max over k, S in grid, levels of measured / formula (k={wmax[1]}, S={wmax[2]:g}, "
        f"level {wmax[3]}); must be <= 1.01", paper=None, formula=1.0, measured=round(wmax[0], 5), unit="ratio",
        source="golden")
    # edges-only test against the formula
    ed_worst = []
    for k in KS:
        n, p = M_BITS - k, 1 << k
        for S in (1.0, 23.3, 1000.0):
            r = _counts(S, n, p, min(M, 5000), test="edges")
            ratio = r.mean[1:] / th.windows(S, n, p)[1:]
            ed_worst.append((float(ratio.max()), k, S, int(ratio.argmax()) + 1))
    ew = max(ed_worst)
    row("fig. 3 / (1)", f"edges-only test: max measured / formula (k={ew[1]}, S={ew[2]:g}, level {ew[3]})",
        paper=None, formula=1.0, measured=round(ew[0], 4), unit="ratio", source="golden")

    # ---------------------------------------------------------------- real polygons
    real_tab = ["| scene | matrix | level i | formula (1), mean over triangles | MC measured (95 %) | "
                "golden search on the frame, per triangle and processor | gap MC |", "|---|---|---|---|---|---|---|"]
    for name in scenes:

        tris = run_geometry(build_scene(name), 512, 512)
        xy = np.asarray(tris.xy)
        n, p = 7, 4  # 512 = 4 * 2**7
        poly, off = mc.triangles_from_scene(xy, M, seed=SEED)
        r = mc.level_counts(poly, off, n, p, test="exact")
        S_t, U_t = _area_perimeter(poly)
        L_t = U_t / (2 * np.sqrt(math.pi * S_t))
        fm = np.zeros(n + 1)
        for s, ell in zip(S_t, L_t, strict=True):
            fm += th.windows(float(s), n, p, L=float(ell))
        fm /= M
        # the recursive search on the frame itself (the scene's own positions)
        fr = sparse_render(tris, (p, p), test="exact")
        T = fr.triangles
        gs = fr.windows / (T * p * p)
        gs_ap = fr.windows_aperture_n / (T * p * p)
        # the formula on the frame's own triangles, per (non-degenerate) triangle
        ff = _formula_frame(xy, n, p) / np.count_nonzero(_area_perimeter(xy)[0] > 1e-6)
        for i in range(1, n + 1):
            g = gs_ap if i == n else gs[i]
            real_tab.append(f"| {name} | 4x4 | {i} | {fm[i]:.4g} | {_fmt_ci(r, i)} | {g:.4g} (formula {ff[i]:.4g}) | "
                            f"{1 - r.mean[i] / fm[i]:+.3f} |")
            row("fig. 3 / (1)", f"{name} triangles, random position and rotation, 4x4, w_{i}, MC {M} "
                f"(±{r.half95[i]:.2g})", paper=None, formula=round(float(fm[i]), 5),
                measured=round(float(r.mean[i]), 5), unit="windows", source="golden")
        row("fig. 3 / (3)", f"{name} frame, 4x4: pixel-level windows (2x2 aperture) per triangle per processor, "
            "recursive search", paper=None, formula=round(float(ff[n]), 5), measured=round(float(gs_ap), 5),
            unit="windows", source="golden")

    # ---------------------------------------------------------------- figs. 5, 6 at S = 1000 and regimes
    Sg = np.logspace(-1, 3, 400)

    def meas_summary(k, S):
        w = spr[k][S].mean
        wm = mono[S].mean
        Ts = th.total_time(w)
        Tso = th.total_time(wm)
        return {"p_s": float(th.perf_stack(w)), "Q_a": float(Tso / ((1 << k) ** 2 * Ts)),
                "p_p": float(th.perf_pipeline(w)), "R_p": float(th.load_pipeline(w)),
                "limiting_level": int(th.limiting_level(w))}

    for k in KS:
        f = th.summary(1000.0, M_BITS, k)
        m_ = meas_summary(k, 1000.0)
        for key, fig in (("p_p", "fig. 6a"), ("Q_a", "fig. 5b"), ("p_s", "fig. 5a"), ("R_p", "fig. 6b")):
            row(fig, f"{key}(S=1000), {1 << k}x{1 << k}", paper=None, formula=round(f[key], 5),
                measured=round(m_[key], 5), unit="", source="model")
    pp = [th.summary(1000.0, M_BITS, k)["p_p"] for k in KS]
    ppm = [meas_summary(k, 1000.0)["p_p"] for k in KS]
    row("fig. 6a text", "p_p(1000) growth per matrix step, (p_p(k=4)/p_p(k=1))^(1/3) (paper: ∝ 4^k)", paper=4.0,
        formula=round((pp[3] / pp[0]) ** (1 / 3), 4), measured=round((ppm[3] / ppm[0]) ** (1 / 3), 4),
        unit="x per k", source="model")
    # the growth per matrix step tends to 4 only as S grows (the limiting stage's 4 w_(n-1) term has
    # the larger relative window alpha_(n-1), whose perimeter term falls slower than 1/pq)
    growth = []
    for S in (1e4, 1e5):
        pf = [th.summary(S, M_BITS, k)["p_p"] for k in KS]
        pm = []
        for k in KS:
            poly, off = mc.rectangles(S, min(M, GROWTH_SAMPLES), seed=SEED)
            pm.append(float(th.perf_pipeline(mc.level_counts(poly, off, M_BITS - k, 1 << k).mean)))
        gf, gm = (pf[3] / pf[0]) ** (1 / 3), (pm[3] / pm[0]) ** (1 / 3)
        growth.append((S, gf, gm))
        row("fig. 6a text", f"p_p(S={S:g}) growth per matrix step, (p_p(k=4)/p_p(k=1))^(1/3) (paper: ∝ 4^k; MC "
            f"{min(M, GROWTH_SAMPLES)})", paper=4.0, formula=round(gf, 4), measured=round(gm, 4), unit="x per k",
            source="model")
    # R_p peak near S_k (fig. 6b): formula on a fine grid; measured on the Monte-Carlo grid
    for k in (2, 3, 4):
        Rp = th.load_pipeline(th.windows(Sg, M_BITS - k, 1 << k))
        Rm = np.array([meas_summary(k, S)["R_p"] for S in S_GRID])
        i, j = int(Rp.argmax()), int(Rm.argmax())
        row("fig. 6b text", f"peak R_p, {1 << k}x{1 << k} (formula at S={Sg[i]:.3g}, measured at S={S_GRID[j]:g}; "
            f"S_k = {th.s_k(k):.3g})", paper=1.0, formula=round(float(Rp[i]), 4), measured=round(float(Rm[j]), 4),
            unit="", source="model")
    # limiting level per regime
    reg = ["| k | S | regime (S_f vs pq) | limiting level, formula | limiting level, measured counts |",
           "|---|---|---|---|---|"]
    for k in KS:
        n = M_BITS - k
        for S in (0.1, 1.8 if k == 2 else (23.3 if k == 3 else (157.0 if k == 4 else 1.0)), 1000.0):
            lf = th.summary(S, M_BITS, k)["limiting_level"]
            lm = meas_summary(k, S)["limiting_level"] if S in spr[k] else None
            Sf = S + 2 * L * math.sqrt(2 * math.pi * S) + 4
            regime = "S_f ≫ pq" if Sf > 4 * 4 ** k else ("S_f ≪ pq" if Sf < 4 ** k / 4 else "S_f ≈ pq")
            reg.append(f"| {k} | {S:g} | {regime} (S_f = {Sf:.3g}, pq = {4 ** k}) | {lf} of {n} | {lm} of {n} |")
            if S in (0.1, 1000.0) and k > 1:
                # the paper names the level ("первыми каскадами", "на пиксельном n-м уровне"); n for a
                # given k is arithmetic, so only the first level is a paper value
                row("fig. 6a text", f"limiting level at S={S:g}, {1 << k}x{1 << k} (n = {n}; paper: first level "
                    f"for S_f ≪ pq, last for S_f ≫ pq)", paper=1 if S < 1 else None, formula=lf, measured=lm,
                    unit="level", source="model")
    lim_ranges = []
    for k in (2, 3, 4):
        lv = th.limiting_level(th.windows(Sg, M_BITS - k, 1 << k))
        inter = Sg[(lv > 1) & (lv < M_BITS - k)]
        lim_ranges.append(f"k = {k}: level 1 up to S = {Sg[lv == 1].max():.3g}, intermediate levels "
                          f"{sorted(set(int(v) for v in lv[(lv > 1) & (lv < M_BITS - k)]))} for S in "
                          f"[{inter.min():.3g}, {inter.max():.3g}], level n = {M_BITS - k} from S = "
                          f"{Sg[lv == M_BITS - k].min():.3g}" if inter.size else f"k = {k}: no intermediate level")

    # ---------------------------------------------------------------- HDL cycles (t_i, R_p)
    hdl_sec = _hdl_rows(row, engine, progress, hdl_scene=known.get("hdl_scene"))
    hdl_sec += _coupled_hdl_rows(row, engine, progress)
    hdl_sec += _paper_load_rows(row, engine, progress)
    large, large_sec = _large_matrix_hdl_rows(engine, fast=fast, progress=progress)
    out += large
    hdl_sec += large_sec

    # ---------------------------------------------------------------- the coupled matrix (golden)
    coupled_sec = _coupled_rows(row, out_dir, size=coupled_size, matrices=coupled_matrices,
                                load_triangles=load_triangles, vp_matrices=coupled_vp_matrices,
                                stack_size=stack_size, scene=coupled_scene, scheduler=scheduler, store=store,
                                fresh=fresh, progress=progress)

    # ---------------------------------------------------------------- stack-based against pipeline processors
    coupled_sec += _stack_vs_pipeline_rows(row, scenes=stack_scenes, sizes=stack_sizes)
    coupled_sec += _stack_hdl_rows(row, engine, scenes=stack_scenes)
    coupled_sec += _stack_matrix_hdl_rows(row, engine)

    # ---------------------------------------------------------------- plots
    plots = _plots(out_dir, spr, mono, Sg, S_GRID)

    sec.append("## Window counts per level: formula (1) against Monte-Carlo\n")
    sec.append(f"5:1 rectangles (L = {L:.4f}) of area S at uniform random position and rotation, {M} samples per "
               f"point, seed {SEED}, exact window test (the window rectangle meets the polygon); 95 % intervals "
               "from the sample standard deviation. m = 10, n = 10 − k, α = β = 2.\n")
    sec.append("\n".join(table) + "\n")
    sec.append("## Real polygons (triangles of the scenes, 512 x 512, 4x4, n = 7)\n")
    sec.append("MC: triangles drawn from the frame with replacement, random rotation and position; the formula is "
               "evaluated per triangle with its own S and L = perimeter / (2 sqrt(pi S)) and averaged. The golden "
               "column is the recursive search on the frame itself (the triangles where the camera put them), "
               "windows per triangle per processor; its level-n entry counts the 2x2-aperture windows.\n")
    sec.append("\n".join(real_tab) + "\n")
    sec.append("## Measured S_k\n")
    sec.append("| k | paper | formula (1) | MC exact test (95 %) | MC edges-only test (95 %) |\n|---|---|---|---|---|\n" +
               "\n".join(f"| {k} | {PAPER_S_K[k - 1]:g} | {th.s_k(k):.4g} | {e[0]:.4g} [{e[1]:.4g}, {e[2]:.4g}] | "
                         f"{d[0]:.4g} [{d[1]:.4g}, {d[2]:.4g}] |" for k, (e, d) in sk_meas.items()) + "\n")
    sec.append("## Why the measured S_k exceed the paper's, and why p_p grows by less than 4 per step\n")
    sec.append("Formula (1)'s perimeter term, sqrt(α_i² + β_i²)·L·sqrt(πS), is the largest over rotations of the "
               "exact mean count's a·H + b·W (W, H the polygon's extents): for a square window it is reached at "
               "45°. Rectangles all at 45° reproduce the paper's S_k; uniform rotations (the table above) need a "
               "larger area for one window; axis-aligned ones larger still.\n\n| k | paper | formula | MC 45° (95 %) | "
               "MC uniform rotation | MC 0° (95 %) |\n|---|---|---|---|---|---|\n" +
               "\n".join(f"| {k} | {PAPER_S_K[k - 1]:g} | {th.s_k(k):.4g} | {sk_rot[(k, '45°')][0]:.4g} "
                         f"[{sk_rot[(k, '45°')][1]:.4g}, {sk_rot[(k, '45°')][2]:.4g}] | {sk_meas[k][0][0]:.4g} | "
                         f"{sk_rot[(k, '0°')][0]:.4g} [{sk_rot[(k, '0°')][1]:.4g}, {sk_rot[(k, '0°')][2]:.4g}] |"
                         for k in KS[1:]) + "\n\n"
               "p_p's growth per step of k: " + "; ".join(f"S = {S:g}: formula ×{gf:.3f}, MC ×{gm:.3f}"
                                                          for S, gf, gm in growth) +
               " (×3.33 at S = 1000, above). The limiting stage is the pixel level, t_n = 4 w_(n−1) + w_n k_p/k_e; "
               "w_n falls as 1/pq but w_(n−1) counts windows of relative size α_(n−1) = (1 + α/p)/2, whose "
               "perimeter and corner terms fall more slowly, so the step tends to 4 only as S grows.\n")
    sec.append("## Limiting level in each regime\n")
    sec.append("\n".join(reg) + "\n\nFrom the formula on a fine grid (S = 0.1 … 1000): " + "; ".join(lim_ranges) + ".\n")
    sec.extend(hdl_sec)
    sec.extend(coupled_sec)
    sec.append("## Figures\n")
    sec.append("\n".join(f"![{t}]({fn})" for t, fn in plots) + "\n")
    return out, sec


def _area_perimeter(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Area S and perimeter U of each triangle of ``xy`` (T, 3, 2)."""
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    S = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    return S, np.linalg.norm(xy - np.roll(xy, -1, 1), axis=2).sum(1)


def _formula_frame(xy: np.ndarray, n: int, p: int) -> np.ndarray:
    """Formula (1) summed over a frame's triangles (each with its own S and L): (n + 1,)."""
    S, U = _area_perimeter(xy)
    good = S > 1e-6
    tot = np.zeros(n + 1)
    for s, u in zip(S[good], U[good], strict=True):
        tot += th.windows(float(s), n, p, L=float(u / (2 * math.sqrt(math.pi * s))))
    return tot


def _hdl_rows(row, engine: str, progress: bool, hdl_scene=None) -> list[str]:
    """Busy cycles per stage of the HDL video processors (τ = one cycle per coverage test)."""
    from rasterhw.sim.sparse.scene import simulate_tris

    if engine == "verilator":
        name = hdl_scene or "c300"
        tris = run_geometry(build_scene(name), 512, 512)
        label = f"{name} 512x512"
    elif engine == "pysim":  # pysim runs ~1 k cycles/s here: a small frame
        tris = random_triangles(64, 64, 40, mean_area=30.0, seed=SEED)
        label = "40 random triangles of 30 px, 64x64"
    else:
        return [f"## HDL cycles\n\nNo HDL rows: engine {engine!r} is not supported by the sparse video processor "
                "(pysim or verilator).\n"]
    p = 4
    r = simulate_tris(tris, (p, p), engine=engine, progress=progress)
    n = r["n"]
    src = f"hdl:{engine}"
    T = r["triangles"]
    hdl_t = np.array(r["tests_per_level_hdl"], dtype=float) / (T * p * p)  # per triangle per processor
    fw = _formula_frame(np.asarray(tris.xy), n, p)  # sums over triangles
    ft = 4.0 * fw[:-1] / T  # the tests term of (5): tau * 4 w_(i-1)
    row("HDL", f"{label}, 4x4: pixels differing from the bit-accurate golden model (of {r['pixels_compared']})",
        paper=None, formula=0, measured=r["mismatches"], unit="pixels", source=src)
    row("HDL", f"{label}, 4x4: busy cycles per stage equal the golden model's coverage tests (1 = yes)",
        paper=None, formula=1, measured=int(r["tests_match_golden"]), unit="", source=src)
    for i in range(1, n + 1):
        row("(5) / HDL", f"{label}, 4x4: t_{i}/τ per triangle per processor (busy cycles of stage {i}; "
            "formula: 4 w_(i-1) of (1))", paper=None, formula=round(float(ft[i - 1]), 4),
            measured=round(float(hdl_t[i - 1]), 4), unit="cycles", source=src)
    Rf0 = float(ft.sum() / (n * ft.max()))
    tf1 = th.stage_times(fw)  # with the k_p/k_e = 1 term, for reference
    Rf1 = float(tf1.sum() / (n * tf1.max()))
    Rh = float(hdl_t.sum() / (n * hdl_t.max()))
    row("(10) / HDL", f"{label}, 4x4: R_p of the frame, sum t_i / (n max t_i) (formula with k_p/k_e = 0 as our "
        f"stage adds parameters in the test cycle; with k_p/k_e = 1: {Rf1:.3f})", paper=None, formula=round(Rf0, 4),
        measured=round(Rh, 4), unit="", source=src)
    row("(9) / HDL", f"{label}, 4x4: frame cycles (slowest processor) / busiest stage's tests", paper=None,
        formula=1.0, measured=round(r["cycles"] / r["max_stage_tests_per_processor"], 4), unit="ratio", source=src)

    gf = sparse_render(tris, (p, p), depth="fixed", trace=True)
    model_cycles = max(vp_standalone(*vp_streams(gf, k), gf.triangles)["cycles"] for k in range(p * p))
    row("HDL", f"{label}, 4x4: slowest processor's cycles, HDL minus the golden cycle model of the video processor "
        f"(golden_model/sparse/vpcycles.py: {model_cycles} cycles; 0 = cycle-exact)", paper=None, formula=0,
        measured=int(r["cycles"]) - model_cycles, unit="cycles", source=src)
    return ["## HDL cycles\n",
            f"`rasterhw sim sparse` run inside this report ({engine}): {label}, 4x4, every processor; "
            f"{r['cycles']} cycles for the slowest processor, {r['sim_cycles']} cycles simulated in all (the "
            "simulation rate is a `rasterhw bench` figure, not a table's); busy cycles (coverage tests) per level summed over processors: "
            f"{r['tests_per_level_hdl']}. A stage makes one coverage test per busy cycle (τ = 1 cycle) and takes "
            "the next window in the cycle of its last test; the frame still takes a little more than its busiest "
            "stage's tests: a triangle's header costs one cycle at every level where it has survivors, and a "
            "full FIFO stalls the stage before it.\n"]


def _plots(out_dir: Path, spr, mono, Sg, S_GRID):  # noqa: N803
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    Sm = np.array(S_GRID)
    # fig. 3: w_i(S) per k
    with saved_figure(out_dir / "sparse_fig3.png", figsize=(11, 8), dpi=90, nrows=2, ncols=2) as axes:
        for ax, k in zip(axes.ravel(), KS, strict=True):
            n, p = M_BITS - k, 1 << k
            w = th.windows(Sg, n, p)
            for i in range(1, n + 1):
                (ln,) = ax.loglog(Sg, w[i], lw=1, label=f"i={i}")
                mm = np.array([spr[k][S].mean[i] for S in S_GRID])
                ax.plot(Sm, mm, "o", ms=3, color=ln.get_color())
            ax.axvline(th.s_k(k) if k > 1 else 0.1, color="k", ls=":", lw=0.8)
            ax.set_title(f"fig. 3: w_i(S), {p}x{p} (lines formula (1), dots Monte-Carlo)")
            ax.set_xlabel("S, px")
            ax.legend(fontsize=6, ncol=2)
    # fig. 4: alpha_i
    with saved_figure(out_dir / "sparse_fig4.png", figsize=(6, 4), dpi=90) as ax:
        for k in KS:
            n = M_BITS - k
            i = np.arange(1, n + 1)
            ax.plot(i, th.alpha_i(i, n, 1 << k), "o-", label=f"{1 << k}x{1 << k}")
        ax.set_xlabel("level i")
        ax.set_ylabel("alpha_i")
        ax.set_title("fig. 4: relative window size (2), alpha = 2")
        ax.legend()
    # figs. 5, 6
    with saved_figure(out_dir / "sparse_fig5_6.png", figsize=(11, 8), dpi=90, nrows=2, ncols=2) as axes:
        for k in KS:
            n, p = M_BITS - k, 1 << k
            w = th.windows(Sg, n, p)
            c = f"C{k - 1}"
            wm = [spr[k][S].mean for S in S_GRID]
            wmo = [mono[S].mean for S in S_GRID]
            axes[0, 0].loglog(Sg, th.perf_stack(w), c, label=f"{p}x{p}")
            axes[0, 0].plot(Sm, [float(th.perf_stack(x)) for x in wm], "o", ms=3, color=c)
            axes[0, 1].semilogx(Sg, th.q_algorithm(Sg, M_BITS, k), c, label=f"{p}x{p}")
            axes[0, 1].plot(Sm, [float(th.total_time(b) / (p * p * th.total_time(a)))
                                 for a, b in zip(wm, wmo, strict=True)], "o", ms=3, color=c)
            axes[1, 0].loglog(Sg, th.perf_pipeline(w), c, label=f"{p}x{p}")
            axes[1, 0].plot(Sm, [float(th.perf_pipeline(x)) for x in wm], "o", ms=3, color=c)
            axes[1, 1].semilogx(Sg, th.load_pipeline(w), c, label=f"R_p {p}x{p}")
            axes[1, 1].semilogx(Sg, th.efficiency_pipeline(Sg, M_BITS, k), c, ls="--")
            axes[1, 1].plot(Sm, [float(th.load_pipeline(x)) for x in wm], "o", ms=3, color=c)
        for ax, t in zip(axes.ravel(), ("fig. 5a: p_s = P_s / P_max", "fig. 5b: Q_a", "fig. 6a: p_p = P_p / P_max",
                                        "fig. 6b: R_p (solid), Q_p (dashed)"), strict=True):
            ax.set_title(t, fontsize=9)
            ax.set_xlabel("S, px")
            ax.legend(fontsize=7)
        axes[0, 0].figure.suptitle("lines: formulas (1)-(12); dots: the same formulas on Monte-Carlo window counts")
    return [("fig. 3", "sparse_fig3.png"), ("fig. 4", "sparse_fig4.png"), ("figs. 5-6", "sparse_fig5_6.png")]


# ---------------------------------------------------------------- the coupled matrix (golden cycle model)
FIFO_DEPTHS = (1, 2, 4, 8, 16, 32, 64)
#: the FIFO depth of the R_p / Q_p / stack / k_p rows (the HDL VP's inner FIFOs are 8 deep)
REF_DEPTH = 8


def _coupled_rows(row, out_dir: Path, *, size: int, matrices: tuple[str, ...], load_triangles: int,
                  vp_matrices: tuple[str, ...] = ("2x2", "4x4", "8x8"), stack_size: int = 512,
                  scene: str = "c300", scheduler: str = "serial", store=None, fresh: bool = False,
                  progress: bool = False) -> list[str]:
    """Frame cycles against FIFO depth, R_p and Q_p from busy cycles, the stack processor and the
    k_p/k_e cost: :mod:`rasterhw.golden_model.sparse.cycles` on the golden search's per-record
    window counts of ``scene`` at ``size`` x ``size`` (the paper's 1024 x 1024 in the report)."""
    from rasterhw.sim.flow.tasks import call, run_tasks

    W = size
    m_bits = W.bit_length() - 1
    tris = run_geometry(build_scene(scene), W, W)
    xy = np.asarray(tris.xy)
    lab = f"{scene} {W}x{W}"
    gp = f"GP issue interval {cy.GP_ISSUE_INTERVAL} cycle (ours)"
    # the golden runs (the monoprocessor, each matrix's coupled sweep, each HDL-processor sweep)
    # are independent tasks (sim/flow/tasks.py: serial by default, any Dask scheduler by address)
    tasks = [call(f"{_SELF}:mono_tests", scene=scene, size=W)]
    tasks += [call(f"{_SELF}:coupled_point", scene=scene, size=W, matrix=m) for m in matrices]
    tasks += [call(f"{_SELF}:coupled_vp_point", scene=scene, size=W, matrix=m) for m in vp_matrices]
    res = run_tasks(tasks, scheduler=scheduler, store=store, fresh=fresh, progress=progress,
                    desc=f"sparse coupled matrix ({lab})")
    T_mono = float(res[0]["tests"])
    points = res[1:1 + len(matrices)]
    vp_points = res[1 + len(matrices):]
    fw_mono = _formula_frame(xy, m_bits, 1)
    curves = {}
    sweep_tab = ["| matrix | FIFO depth D | frame cycles | / unbounded FIFO | broadcast stall cycles | FIFO peak (max) | "
                 "busy / frame, least and most loaded processor |", "|---|---|---|---|---|---|---|"]
    rp_tab = ["| matrix | n | R_p golden (frame) | R_p formula (10), k_p/k_e = 0 | R_p coupled, D = 8 | Q_a golden | "
              "Q_a formula (7) | Q_p golden | Q_p formula (12) | stack / pipeline frame | formula n R_p |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    kp_tab: list[str] = []
    for m, pt in zip(matrices, points, strict=True):
        p = int(m.split("x")[0])
        P = p * p
        n = pt["n"]
        alone = pt["alone"]
        fr = {}
        for D, r in zip(FIFO_DEPTHS, pt["depths"], strict=True):
            fr[D] = r["frame_cycles"]
            sweep_tab.append(f"| {m} | {D} | {r['frame_cycles']} | {r['frame_cycles'] / alone:.4f} | "
                             f"{r['stall_cycles']} | {r['fifo_peak_max']} | {r['util_min']:.3f} … {r['util_max']:.3f} |")
            row("FIFO sizing (coupled)", f"{lab}, {m}: frame cycles, FIFO depth {D} (pipeline VPs, {gp})",
                paper=None, formula=None, measured=r["frame_cycles"], unit="cycles", source="golden")
            if D == 1:
                row("FIFO sizing (coupled)", f"{lab}, {m}: broadcast stall cycles, FIFO depth 1", paper=None,
                    formula=None, measured=r["stall_cycles"], unit="cycles", source="golden")
        sweep_tab.append(f"| {m} | unbounded | {alone} | 1 | 0 | — | — |")
        curves[m] = [fr[D] / alone for D in FIFO_DEPTHS]
        for D in (1, 8, 64):
            row("FIFO sizing (coupled)", f"{lab}, {m}: frame with FIFO depth {D} / frame with an unbounded FIFO "
                "(the slowest processor alone; paper's assumption: coupling small with enough FIFO)",
                paper=None, formula=None, measured=round(fr[D] / alone, 5), unit="ratio", source="golden")
        d1 = next((D for D in FIFO_DEPTHS if fr[D] <= 1.01 * alone), None)
        row("FIFO sizing (coupled)", f"{lab}, {m}: smallest FIFO depth (of 1 … 64) within 1 % of the unbounded "
            "frame", paper=None, formula=None, measured=d1 if d1 is not None else -1, unit="entries",
            source="golden")
        # R_p, Q_a, Q_p from busy cycles (pipeline VP as our HDL prices it: headers, k_p = 0)
        Bi = np.asarray(pt["stage_busy"], dtype=float)  # busy cycles per stage, summed over processors
        Rp = float(Bi.sum() / (n * Bi.max()))
        fw = _formula_frame(xy, n, p)
        tf = th.stage_times(fw, kp_ke=0.0)
        Rp_f = float(tf.sum() / (n * tf.max()))
        Rp_c = float(Bi.sum() / (n * P * pt["ref_frame"]))
        Qa = T_mono / float(pt["tests"])
        Qa_f = float(th.total_time(fw_mono, kp_ke=0.0) / (P * th.total_time(fw, kp_ke=0.0)))
        row("(10) / golden", f"{lab}, {m}: R_p = sum_i B_i / (n max_i B_i) from the golden pipeline's busy cycles "
            "B_i per stage (summed over processors; header cycles included; formula: (10) on (1)'s counts for "
            "the frame's triangles, k_p/k_e = 0)", paper=None, formula=round(Rp_f, 4), measured=round(Rp, 4),
            unit="", source="golden")
        row("(10) / golden", f"{lab}, {m}: R_p of the coupled frame, sum_i B_i / (n P frame cycles), FIFO depth "
            f"{REF_DEPTH} (load including the coupling and the processors' imbalance)", paper=None,
            formula=round(Rp_f, 4), measured=round(Rp_c, 4), unit="", source="golden")
        row("(7) / golden", f"{lab}, {m}: Q_a = T_mono / (pq T_sparse), coverage tests of the golden search "
            "(monoprocessor: 1x1 on the full raster, n = 10; formula (7) on (1)'s counts, k_p/k_e = 0)",
            paper=None, formula=round(Qa_f, 4), measured=round(Qa, 4), unit="", source="golden")
        row("(12) / golden", f"{lab}, {m}: Q_p = Q_a R_p (golden busy cycles; formula (12))", paper=None,
            formula=round(Qa_f * Rp_f, 4), measured=round(Qa * Rp, 4), unit="", source="golden")
        # the stack-based processor on the same frame
        sp_st = pt["stack_frame"] / pt["ref_frame"]
        tf0h = th.stage_times(fw, kp_ke=0.0)
        row("(10) / stack", f"{lab}, {m}: frame cycles of the stack-based processors, FIFO depth {REF_DEPTH} "
            f"(set-up {cy.SETUP_CYCLES} + every coverage test, one per cycle)", paper=None, formula=None,
            measured=pt["stack_frame"], unit="cycles", source="golden")
        row("(10) / stack", f"{lab}, {m}: stack frame / pipeline frame, FIFO depth {REF_DEPTH} (formula: "
            "P_p / P_s = n R_p of (10) on (1)'s counts, k_p/k_e = 0)", paper=None,
            formula=round(float(tf0h.sum() / tf0h.max()), 4), measured=round(sp_st, 4), unit="ratio",
            source="golden")
        rp_tab.append(f"| {m} | {n} | {Rp:.4f} | {Rp_f:.4f} | {Rp_c:.4f} | {Qa:.4f} | {Qa_f:.4f} | {Qa * Rp:.4f} | "
                      f"{Qa_f * Rp_f:.4f} | {sp_st:.3f} | {tf0h.sum() / tf0h.max():.3f} |")
        if m == "4x4":
            # surface parameters priced as (5): depth and RGB (k_p = 4) on the k_e = 3 edge adders
            for vp in ("pipeline", "stack"):
                f0, f4 = pt["kp_frames"][vp]
                t0, t4 = th.stage_times(fw, kp_ke=0.0), th.stage_times(fw, kp_ke=4 / 3)
                ff = float(t4.max() / t0.max()) if vp == "pipeline" else float(t4.sum() / t0.sum())
                row("(5) k_p/k_e", f"{lab}, {m}: frame with depth and RGB priced (k_p = 4, k_e = 3: "
                    f"ceil(w_i k_p / k_e) cycles per stage and record) / unpriced, {vp} VPs, FIFO depth "
                    f"{REF_DEPTH} (formula: (5) on (1)'s counts, k_p/k_e = 4/3 against 0)", paper=None,
                    formula=round(ff, 4), measured=round(f4 / f0, 4), unit="ratio", source="golden")
                kp_tab.append(f"{vp}: {f0} → {f4} cycles (×{f4 / f0:.3f}; formula ×{ff:.3f})")
    vp_tab = _coupled_vp_rows(row, lab, vp_matrices, vp_points)
    stack_txt = _stack_rows(row, scene, stack_size)
    gp_tab = _gp_rate_rows(row, scene, stack_size)
    load_tab = _load_rows(row, W, load_triangles)
    plot = _fifo_plot(out_dir, curves, lab)
    return ["## The coupled matrix: FIFO sizing (golden cycle model)\n",
            f"`golden_model/sparse/cycles.py` on the golden search's per-record window counts of {lab} "
            f"(records in submission order). One geometry processor offers a record every {cy.GP_ISSUE_INTERVAL} "
            "cycle (ours: the paper gives no rate, so the broadcast is never the bottleneck and every stall is the "
            "processors'); a record is pushed into all p·q FIFOs only when each has room; a pipeline video "
            "processor holds a record for its busiest stage's cycles (4 w_(i−1) tests plus a header cycle where "
            "the triangle has survivors; (9)), a stack processor for all of its tests plus a 3-cycle set-up. "
            "'unbounded' is the slowest processor alone, plus the one-cycle push.\n",
            "\n".join(sweep_tab) + "\n",
            "R_p, Q_a and Q_p from the golden busy cycles beside the paper's (10), (7), (12) evaluated with "
            "formula (1)'s counts for the same triangles (each with its own S and L), k_p/k_e = 0 as our stage "
            f"prices it. Coupled R_p at FIFO depth {REF_DEPTH}.\n",
            "\n".join(rp_tab) + "\n",
            "Surface parameters priced as formula (5) (4x4, FIFO depth 8): " + "; ".join(kp_tab) + ".\n",
            "## The coupled matrix with the HDL video processors (golden cycle model of the processor as built)\n",
            "`vpcycles.coupled_matrix_vp`: the same broadcast, FIFO and counting rules, each processor the cycle "
            "model of `hdl/sparse/vp.py` (set-up FSM, level stages, inner FIFOs, pixel processor), "
            "which equals the HDL cycle for cycle (pysim tests; Verilator per-processor cycles in the HDL rows). "
            "Two processors: the paper's, whose queue of primitives is its input FIFO (\"Память типа FIFO на входе "
            "хранит очередь описаний\"; two-entry buffers between its stages, the default of `rasterhw sim "
            "sparse`), and ours, with eight-entry FIFOs between the levels: a queue of windows inside the "
            "processor, which makes the input FIFO's depth matter far less.\n",
            "\n".join(vp_tab) + "\n",
            "## A geometry processor only as fast as the matrix\n",
            "The GP issue interval is ours. With g = 1 the GP is never the bottleneck; here it offers a record "
            "every g = ceil(slowest processor alone / records) cycles, the matrix's mean rate, so the FIFOs must "
            "also absorb the processors' record-to-record variation against the GP (the paper: the queues "
            "\"способствует ослаблению связей ... между матрицей и геометрическим процессором\").\n",
            "\n".join(gp_tab) + "\n",
            "## The stack-based processor's golden model\n", stack_txt,
            "## Where \"practically 100 %\" load holds (fig. 6b)\n",
            f"Frames of {load_triangles} random triangles (`reference.random_triangles`, seed {SEED}, {W} x {W}) "
            "of one mean area: "
            "at the paper's S_k and at 1000 px. R_p from the golden search's per-record counts of the frame priced "
            "as the paper prices them (formula (5) with k_p/k_e = 1, no header cycles; source `model`), beside "
            "(10) on formula (1)'s counts for the same triangles.\n",
            "\n".join(load_tab) + "\n",
            f"![FIFO sizing]({plot})\n"]


_SELF = "rasterhw.sim.sparse.report"

#: the two video processors of the coupled sweeps, both ours (the paper gives no buffer size: it
#: asks only for a "sufficient" input FIFO, "достаточном объеме FIFO", and refers the
#: micro-pipeline to its reference [3]): key (of :func:`coupled_vp_point`), label in the rows, depth
#: of the FIFOs between the levels. The default (first) is the eight-entry one, the depth that
#: reproduces formulas (9) and (10) (rows "(9) / (10), HDL frame time"); two entries is the
#: shallowest buffer the HDL takes
_VP_CONFIGS = (("eight", "eight-entry inner FIFOs (ours, the default)", HDL_FIFO_DEPTH),
               ("two", "two-entry inner buffers (ours)", SHALLOW_FIFO_DEPTH))


def _vp_depths(matrix: str) -> tuple[int, ...]:
    return (1, 8, 64) if matrix == "4x4" else (1, 64)


def mono_tests(scene: str, size: int) -> dict:
    """Coverage tests of the monoprocessor (1x1 on the full raster) on ``scene`` at ``size``^2 (a task)."""

    tris = run_geometry(build_scene(scene), size, size)
    return {"tests": int(sparse_render(tris, "1x1", depth="fixed").tests.sum())}


def coupled_point(scene: str, size: int, matrix: str) -> dict:
    """One matrix of the coupled FIFO sweep (a task): the golden cycle model of pipeline video
    processors at every FIFO depth, the busy cycles per stage, the stack-based processors' frame,
    and on 4x4 the frames with surface parameters priced as (5)."""

    tris = run_geometry(build_scene(scene), size, size)
    f = sparse_render(tris, matrix, depth="fixed", per_record=True)
    w = f.stats["windows_per_record"]
    s_pipe = cy.service_times(w)
    depths = []
    for D in FIFO_DEPTHS:
        r = cy.coupled_matrix(s_pipe, D)
        util = r.busy / r.frame_cycles
        depths.append({"frame_cycles": int(r.frame_cycles), "stall_cycles": int(r.stall_cycles),
                       "fifo_peak_max": int(r.fifo_peak.max()), "util_min": float(util.min()),
                       "util_max": float(util.max())})
    s_st = cy.service_times(w, vp="stack")
    out = {"n": int(f.n), "alone": int(1 + s_pipe.sum(axis=1).max()), "depths": depths,
           "stage_busy": [int(v) for v in cy.stage_cycles(w).sum(axis=1).sum(axis=0)],
           "ref_frame": int(cy.coupled_matrix(s_pipe, REF_DEPTH).frame_cycles),
           "stack_frame": int(cy.coupled_matrix(s_st, REF_DEPTH).frame_cycles), "tests": int(f.tests.sum())}
    if matrix == "4x4":
        out["kp_frames"] = {vp: [int(cy.coupled_matrix(s0, REF_DEPTH).frame_cycles),
                                 int(cy.coupled_matrix(cy.service_times(w, vp=vp, kp=4), REF_DEPTH).frame_cycles)]
                            for vp, s0 in (("pipeline", s_pipe), ("stack", s_st))}
    return out


def coupled_vp_point(scene: str, size: int, matrix: str) -> dict:
    """One matrix of the coupled sweep whose processors are the HDL video processor's cycle model
    (a task): frame cycles, stalls, largest FIFO peak and least busy processor per FIFO depth, for
    both processors of :data:`_VP_CONFIGS` (eight-entry inner FIFOs, ``"eight"``; two-entry, ``"two"``)."""

    tris = run_geometry(build_scene(scene), size, size)
    f = sparse_render(tris, matrix, depth="fixed", trace=True)
    out = {}
    for key, _who, vpd in _VP_CONFIGS:
        pts = out[key] = []
        for D in _vp_depths(matrix):
            r = coupled_matrix_vp(f, D, fifo_depth=vpd)
            pts.append({"frame_cycles": int(r["frame_cycles"]), "stall_cycles": int(r["stall_cycles"]),
                        "fifo_peak_max": int(r["fifo_peak_max"]), "busy_min": int(min(r["busy"]))})
    return out


def _coupled_vp_rows(row, lab: str, matrices: tuple[str, ...], points: list[dict]) -> list[str]:
    """Frame cycles, stalls and FIFO peaks of the coupled matrix whose processors are the HDL video
    processor's cycle model, at FIFO depths 1 and 64 (and 8 on 4x4), for both processors of
    :data:`_VP_CONFIGS`: rows from :func:`coupled_vp_point`'s results."""
    tab = ["| matrix | processor | FIFO depth D | frame cycles | broadcast stall cycles | FIFO peak (max) | "
           "processor busy / frame, least loaded |", "|---|---|---|---|---|---|---|"]
    for m, pt in zip(matrices, points, strict=True):
        for key, who, _vpd in _VP_CONFIGS:
            fr = {}
            q = f"{lab}, {m}, {who}"
            for D, r in zip(_vp_depths(m), pt[key], strict=True):
                fr[D] = r["frame_cycles"]
                tab.append(f"| {m} | {who} | {D} | {r['frame_cycles']} | {r['stall_cycles']} | "
                           f"{r['fifo_peak_max']} | {r['busy_min'] / r['frame_cycles']:.3f} |")
                row("FIFO sizing (coupled, HDL VPs)", f"{q}: frame cycles, FIFO depth {D} (video processors: "
                    "the HDL's cycle model)", paper=None, formula=None, measured=r["frame_cycles"], unit="cycles",
                    source="golden")
                row("FIFO sizing (coupled, HDL VPs)", f"{q}: broadcast stall cycles, FIFO depth {D}",
                    paper=None, formula=None, measured=r["stall_cycles"], unit="cycles", source="golden")
                row("FIFO sizing (coupled, HDL VPs)", f"{q}: largest FIFO peak, FIFO depth {D} (never above D)",
                    paper=None, formula=None, measured=r["fifo_peak_max"], unit="entries", source="golden")
            row("FIFO sizing (coupled, HDL VPs)", f"{q}: frame with FIFO depth 1 / with depth 64", paper=None,
                formula=None, measured=round(fr[1] / fr[64], 5), unit="ratio", source="golden")
    return tab


def _gp_rate_rows(row, scene: str, size: int) -> list[str]:
    """Frame cycles against FIFO depth with the GP issuing at the matrix's mean rate (4x4), for the
    pipeline-as-server model and for the HDL video processors' cycle model."""

    tris = run_geometry(build_scene(scene), size, size)
    f = sparse_render(tris, "4x4", depth="fixed", trace=True, per_record=True)
    alone = cy.matrix_cycles(f, f.triangles)["slowest_alone"]
    g = -(-alone // f.triangles)
    lab = f"{scene} {size}x{size}, 4x4, GP issue interval {g} (= ceil({alone} / {f.triangles}), ours)"
    tab = [f"{lab}; the GP alone needs {g * f.triangles} cycles.\n", "| FIFO depth D | frame, pipeline as server | "
           "stall cycles | frame, HDL video processors | stall cycles |", "|---|---|---|---|---|"]
    for D in (1, 4, 16, 64):
        sv = cy.matrix_cycles(f, D, issue_interval=g)
        hv = coupled_matrix_vp(f, D, issue_interval=g)
        tab.append(f"| {D} | {sv['frame_cycles']} | {sv['stall_cycles']} | {hv['frame_cycles']} | "
                   f"{hv['stall_cycles']} |")
        for name, r in (("pipeline VPs as servers", sv), ("HDL video processors' cycle model", hv)):
            row("FIFO sizing (GP at the matrix's rate)", f"{lab}: frame cycles, FIFO depth {D}, {name}", paper=None,
                formula=None, measured=r["frame_cycles"], unit="cycles", source="golden")
    return tab


def _stack_rows(row, scene: str, size: int) -> str:
    """Every processor of a 4x4 matrix as a stack processor (depth first) on ``scene`` at ``size``:
    image against the breadth-first golden search, its stack depth, its cycles against the stack
    cycle model."""

    tris = run_geometry(build_scene(scene), size, size)
    p = 4
    f = sparse_render(tris, (p, p), depth="fixed", per_record=True)
    gz = f.depth_words(tris.z_bits)
    s = cy.service_times(f.stats["windows_per_record"], vp="stack")
    diff, same_cycles, deepest, n = 0, True, 0, f.n
    for b in range(p):
        for a in range(p):
            r = stack_processor(tris, (p, p), a, b)
            diff += int(np.count_nonzero((r["tri"] != f.local_tri[b, a]) | (r["zq"] != gz[b::p, a::p])))
            same_cycles &= bool(np.array_equal(r["cycles"], s[b * p + a]))
            deepest = max(deepest, r["max_stack"])
    lab = f"{scene} {size}x{size}, 4x4"
    row("(8) / stack", f"{lab}: pixels of the stack processors' local memories differing from the breadth-first "
        f"golden search (of {f.tri_id.size})", paper=None, formula=0, measured=diff, unit="pixels", source="golden")
    row("(8) / stack", f"{lab}: stack processors' cycles per record equal the stack cycle model (1 = yes)",
        paper=None, formula=1, measured=int(same_cycles), unit="", source="golden")
    row("(8) / stack", f"{lab}: deepest stack over every processor and record (formula: the bound 3 (n - 1))",
        paper=None, formula=3 * (n - 1), measured=deepest, unit="entries", source="golden")
    return (f"`golden_model/sparse/stack.py` ran every processor of {lab} depth first: {diff} pixels differ from the "
            f"breadth-first search, its per-record cycles {'equal' if same_cycles else 'DIFFER from'} the stack "
            f"cycle model's, and the deepest stack held {deepest} windows (bound {3 * (n - 1)}).\n")


#: the matrix input FIFO depth of the stack-against-pipeline rows (the HDL matrix's default build)
STACK_CMP_DEPTH = 64


def _stack_vs_pipeline_rows(row, *, scenes: tuple[str, ...], sizes: tuple[int, ...], matrix: str = "4x4") -> list[str]:
    """The same frames through a 4x4 matrix of stack-based processors and of pipeline processors:
    frame cycles, each processor's load (busy / frame, least and most loaded) and the load of its
    coverage-test units (stack: one unit, tests / frame; pipeline: n stage units, sum of the stages'
    tests / (n frame), the frame's R_p). Stack: the golden stack cycle model (3 + tests per record; the
    HDL ``StackProcessor`` is cycle-exact with it). Pipeline: the golden cycle model of the HDL video
    processor as built (``vpcycles.coupled_matrix_vp``, cycle-exact with ``hdl/sparse/vp.py``) and the
    pipeline as a server of (9)."""

    D = STACK_CMP_DEPTH
    fig = "(8) / (9) stack vs pipeline"
    tab = [f"Matrix {matrix}, input FIFO depth {D}, GP issue interval {cy.GP_ISSUE_INTERVAL} (ours). Processor load = "
           "busy cycles / frame cycles (least … most loaded processor); unit load = coverage tests / (units × frame), "
           "mean over processors (stack: 1 unit; pipeline: n units, one per level).\n",
           "| frame | processor | frame cycles | / pipeline (HDL) | processor load | unit load |",
           "|---|---|---|---|---|---|"]
    for scene in scenes:
        for W in sizes:
            tris = run_geometry(build_scene(scene), W, W)
            f = sparse_render(tris, matrix, depth="fixed", trace=True, per_record=True)
            n = f.n
            w = f.stats["windows_per_record"]
            tests = f.tests_per_proc[:, 1:].sum(axis=1).astype(float)  # (P,) coverage tests per processor
            lab = f"{scene} {W}x{W}, {matrix}"
            hv = coupled_matrix_vp(f, D)
            runs = {"pipeline (HDL VP cycle model)": (hv["frame_cycles"], np.array(hv["busy"], dtype=float), n)}
            for vp, name, kp in (("pipeline", "pipeline as a server (9)", 0),
                                 ("stack", "stack (golden = HDL stack processor)", 0),
                                 ("stack", "stack, depth + RGB priced as (5), k_p = 4, k_e = 3", 4)):
                r = cy.coupled_matrix(cy.service_times(w, vp=vp, kp=kp), D)
                runs[name] = (r.frame_cycles, r.busy.astype(float), 1 if vp == "stack" else n)
            ref = hv["frame_cycles"]
            for name, (fr, busy, units) in runs.items():
                load = busy / fr
                ul = float((tests / (units * fr)).mean())
                tab.append(f"| {lab} | {name} | {fr} | {fr / ref:.3f} | {load.min():.4f} … {load.max():.4f} | {ul:.4f} |")
                row(fig, f"{lab}: frame cycles, {name}, input FIFO depth {D}", paper=None, formula=None, measured=fr,
                    unit="cycles", source="golden")
                row(fig, f"{lab}: least loaded processor's busy / frame, {name}", paper=None, formula=None,
                    measured=round(float(load.min()), 4), unit="", source="golden")
                row(fig, f"{lab}: coverage-test unit load, tests / (units x frame), {name} ({units} unit"
                    f"{'s' if units > 1 else ''})", paper=None, formula=None, measured=round(ul, 4), unit="",
                    source="golden")
            st = runs["stack (golden = HDL stack processor)"][0]
            tf = th.stage_times(_formula_frame(np.asarray(tris.xy), n, f.p), kp_ke=0.0)
            row(fig, f"{lab}: stack frame / pipeline frame (HDL VP cycle model) (formula: P_p / P_s = n R_p of (10) "
                "on (1)'s counts, k_p/k_e = 0)", paper=None, formula=round(float(tf.sum() / tf.max()), 4),
                measured=round(st / ref, 4), unit="ratio", source="golden")
    return ["## Stack-based against pipeline processors on the same frames\n", "\n".join(tab) + "\n"]


def _stack_hdl_rows(row, engine: str, *, scenes: tuple[str, ...]) -> list[str]:
    """The HDL stack processor (``hdl/sparse/stack_vp.py``, block ``sparse-stack-vp``) on the engines'
    testbench: processor (3, 3) of a 4x4 matrix on each scene at 512² (Verilator), or a small random
    frame (pysim): pixels and counters (busy cycles, records, stack depth, writes, tests per level)
    against the golden stack processor."""
    from rasterhw.sim.engines import run
    from rasterhw.sim.sparse.testbench import StackVPBench

    if engine == "verilator":
        cases = [(f"{sc} 512x512, 4x4", run_geometry(build_scene(sc), 512, 512), 4) for sc in scenes]
    elif engine == "pysim":
        cases = [("20 random triangles of 40 px, 32x32, 2x2", random_triangles(32, 32, 20, mean_area=40.0, seed=SEED), 2)]
    else:
        return [f"## The stack-based processor in HDL\n\nNo rows: engine {engine!r} is not supported (pysim or "
                "verilator).\n"]
    tb = StackVPBench()
    src = f"hdl:{engine}"
    tab = ["| frame | processor | configuration | pixels differing | counters differing | busy cycles HDL | "
           "golden | deepest stack |", "|---|---|---|---|---|---|---|---|"]
    for lab, tris, p in cases:
        n = (tris.width // p).bit_length() - 1
        for conf, kw in (("depth, k_p = 0", {}), ("depth + RGB, k_p = 4, k_e = 3 (5)", {"colour": True, "kp": 4})):
            prm = tb.params(n=n, p=p, q=p, **kw)
            stim = StackVPBench.records(tris, prm, what=lab)
            exp = tb.expect(prm, stim)
            got = run(tb, prm, stim, engine=engine, expect_words={"o": len(exp.words["o"])})
            words = 1 << (2 * n)
            e, g = exp.words["o"], got.words["o"]
            pix = sum(int(x != y) for x, y in zip(e[:words], g[:words], strict=True))
            cnt = sum(int(x != y) for x, y in zip(e[words:], g[words:], strict=True))
            names = StackVPBench.counters(n)
            hb, gb = g[words + names.index("busy_cycles")], e[words + names.index("busy_cycles")]
            proc = f"({p - 1}, {p - 1})"
            tab.append(f"| {lab} | {proc} | {conf} | {pix} | {cnt} of {len(names)} | {hb} | {gb} | "
                       f"{g[words + names.index('max_stack')]} |")
            what = "triangle and depth" + (" and colour" if kw else "")
            for qty, v, unit in ((f"local-memory words ({what}) of the HDL stack processor differing from the "
                                  f"golden stack processor (of {words})", pix, "pixels"),
                                 ("counters of the HDL stack processor differing from the golden model (busy "
                                  f"cycles, records, stack depth, writes, tests per level: {len(names)})", cnt,
                                  "counters"),
                                 ("busy cycles of the HDL stack processor (golden: 3 + tests + parameter cycles per "
                                  "record)", hb, "cycles")):
                row("(8) / stack HDL", f"{lab}, processor {proc}, {conf}: {qty}", paper=None, formula=None,
                    measured=v, unit=unit, source=src)
    return ["## The stack-based processor in HDL\n",
            "`hdl/sparse/stack_vp.py` (`StackProcessor`, block `sparse-stack-vp`) on the engines' testbench "
            "(`sim/sparse/testbench.py` `StackVPBench`): the broadcast records back to back, then its local memory and "
            "its counters read out, against `golden_model/sparse/stack.py`.\n", "\n".join(tab) + "\n"]


def _stack_matrix_hdl_rows(row, engine: str) -> list[str]:
    """The coupled matrix of HDL stack processors (``hdl/sparse/matrix.py``, ``vp="stack"``, one
    simulation) at input FIFO depths 64 and 1: frame cycles, broadcast stalls and FIFO peaks against
    the golden coupled model on the stack service times (plus the last pixels' drain)."""
    from rasterhw.sim.sparse.scene import run_matrix

    if engine == "verilator":
        W, p, lab, depths = 512, 4, "c300 512x512, 4x4", (64, 1)
        run = lambda recs, **kw: run_matrix(tris, **kw)  # noqa: E731 - the records are the frame's
        tris = run_geometry(build_scene("c300"), W, W)
    elif engine == "pysim":  # its input FIFOs built 8 deep
        W, p, lab, depths = 16, 2, "12 random triangles of 16 px, 16x16, 2x2", (8, 1)
        run = lambda recs, **kw: run_matrix(tris, **kw, in_depth=8, engine="pysim")  # noqa: E731
        tris = random_triangles(W, W, 12, mean_area=16.0, seed=SEED)
    else:
        return []
    src = f"hdl:{engine}"
    f = sparse_render(tris, (p, p), depth="fixed", per_record=True)
    gz = f.depth_words(tris.z_bits)
    s = cy.service_times(f.stats["windows_per_record"], vp="stack")
    tail = np.stack([stack_processor(tris, (p, p), k % p, k // p)["tail"] for k in range(p * p)])
    tab = ["| input FIFO depth | frame cycles, HDL | golden | stall cycles, HDL | golden | FIFO peak, HDL = golden | "
           "pixels differing | busy and tests equal |", "|---|---|---|---|---|---|---|---|"]
    frames = {}
    for D in depths:
        h = run(broadcast_records(tris), n=f.n, p=p, q=p, limit=D, z_bits=tris.z_bits, vp="stack")
        g = cy.coupled_matrix(s, D)
        gf = int((g.pop + s + tail).max())
        pix = int(np.count_nonzero((h["tri"] != f.tri_id) | (h["zq"] != gz)))
        peak_ok = h["stats"]["fifo_peak"].tolist() == g.fifo_peak.tolist()
        tests = np.stack([h["stats"][f"tests_{i}"] for i in range(1, f.n + 1)], axis=1)
        same = h["stats"]["busy_cycles"].tolist() == g.busy.tolist() and np.array_equal(tests, f.tests_per_proc[:, 1:])
        tab.append(f"| {D} | {h['cycles']} | {gf} | {h['stall_cycles']} | {g.stall_cycles} | "
                   f"{int(h['stats']['fifo_peak'].max())} ({'=' if peak_ok else '≠'}) | {pix} | {'yes' if same else 'NO'} |")
        for qty, v, unit in (("frame cycles (golden: coupled model on the stack service times plus the last "
                              "pixels' drain)", h["cycles"], "cycles"),
                             ("frame cycles HDL minus golden", h["cycles"] - gf, "cycles"),
                             ("broadcast stall cycles HDL minus golden", h["stall_cycles"] - g.stall_cycles, "cycles"),
                             (f"pixels differing from the golden search (of {f.tri_id.size})", pix, "pixels")):
            row("(8) / stack HDL matrix", f"{lab}: coupled matrix of HDL stack processors, input FIFO depth {D}: "
                f"{qty}", paper=None, formula=None, measured=v, unit=unit, source=src)
        frames[D] = h["cycles"]
    # Q_a (7) from HDL frame time: the monoprocessor with a stack on the full raster against p q
    # processors with stacks, Q_a = T_so / (pq T_s), T_s the HDL frame at the deepest input FIFO
    Dq = max(depths)
    T_so = _mono_stack_cycles(tris)
    fw = _formula_frame(np.asarray(tris.xy), f.n, p)
    fw_mono = _formula_frame(np.asarray(tris.xy), (tris.width - 1).bit_length(), 1)
    Qa_f = float(th.total_time(fw_mono, kp_ke=0.0) / (p * p * th.total_time(fw, kp_ke=0.0)))
    row("(7) / HDL frame time", f"{lab}: Q_a from HDL frame time, T_so / (pq frame cycles of the HDL stack matrix), "
        f"input FIFO depth {Dq} (T_so: the monoprocessor with a stack on the full raster, golden stack cycle model "
        f"{T_so:.0f}; formula: (7) on (1)'s counts, k_p/k_e = 0)", paper=None, formula=round(Qa_f, 4),
        measured=round(T_so / (p * p * frames[Dq]), 4), unit="", source=src)
    return ["## The coupled matrix of stack processors in HDL\n",
            f"`hdl/sparse/matrix.py` with `vp=\"stack\"` on {lab}, one simulation ({engine}), against "
            "`cycles.coupled_matrix` on the stack processors' service times; the HDL frame ends when the last "
            "pixel leaves the pixel processor (the golden model's per-record drain, `stack_processor`'s `tail`).\n",
            "\n".join(tab) + "\n"]


def _mono_stack_cycles(tris) -> float:
    """T_so: cycles of the monoprocessor with a stack on the full raster (1x1), the golden stack cycle
    model (``cycles.service_times(vp="stack")``: set-up + every coverage test, per record; the HDL
    stack processor is cycle-exact with it), summed over the frame's records."""

    f = sparse_render(tris, "1x1", depth="fixed", per_record=True)
    return float(cy.service_times(f.stats["windows_per_record"], vp="stack").sum())


#: the paper's load and maximum-performance claims measured in coupled HDL runs of random triangles of
#: the paper's S_k: (matrix, raster side, triangles) per engine (Verilator: the issue's 3,000 triangles
#: at 256 x 256; pysim: a small frame that runs in seconds)
LOAD_RUNS = {"verilator": (("4x4", 256, 3000), ("8x8", 256, 3000)), "pysim": (("4x4", 32, 150),)}


def _paper_load_rows(row, engine: str, progress: bool) -> list[str]:
    """Load ("практически до 100 %" near S = S_k, fig. 6b) and time per primitive ("в среднем времени пяти
    тестов покрытия" at maximum performance, conclusion) from coupled HDL runs (default processor,
    input FIFO depth 64) of random triangles of mean area S_k: load = sum of the stages' busy cycles
    (HDL tests per level + header cycles counted from the golden search) / (n P frame cycles); time per
    primitive = HDL frame cycles (before read-out) / primitives, in coverage-test times (tau = 1 cycle)."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    if engine not in LOAD_RUNS:
        return []
    src = f"hdl:{engine}"
    tab = ["| matrix | frame | S_k | frame cycles, HDL | load (tests + headers) | load (tests) | cycles per primitive |",
           "|---|---|---|---|---|---|---|"]
    for m, W, ntri in LOAD_RUNS[engine]:
        p = int(m.split("x")[0])
        k = p.bit_length() - 1
        S = PAPER_S_K[k - 1]
        tris = random_triangles(W, W, ntri, mean_area=S, seed=SEED)
        r = simulate_coupled(tris, m, engine=engine, fifo_depth=64, progress=progress)
        if r["mismatches"] or r["cycle_mismatches"]:
            raise RuntimeError(f"sparse {m} at S_k: HDL differs from the golden model ({r['mismatches']} pixels, "
                               f"{r['cycle_mismatches']} counters)")
        g = sparse_render(tris, (p, p), depth="fixed", per_record=True)
        B = cy.stage_cycles(g.stats["windows_per_record"]).sum(axis=1).astype(float)   # (P, n)
        n, fr, T = r["n"], r["frame_cycles"], r["triangles"]
        load = float(B.sum() / (n * p * p * fr))
        load_t = float(np.sum(r["tests_per_level_hdl"]) / (n * p * p * fr))
        lab = f"{ntri} random triangles of mean area S_{k} = {S:g} px, {W}x{W}, {m}, eight-entry inner FIFOs, " \
              "input FIFO depth 64"
        row("fig. 6b text", f"{lab}: load of the pipelines from HDL frame time, sum of stage busy cycles (HDL tests + "
            "header cycles) / (n P frame cycles) (paper: maximum 'practically up to 100 %' near S_k)",
            paper=PAPER_LOAD_MAX, formula=None, measured=round(load, 4), unit="", source=src)
        row("fig. 6b text", f"{lab}: load of the pipelines from HDL frame time, coverage tests only",
            paper=PAPER_LOAD_MAX, formula=None, measured=round(load_t, 4), unit="", source=src)
        row("conclusion", f"{lab}: frame cycles per primitive, HDL (tests per primitive at maximum performance, tau "
            "= 1 cycle; paper: 'on average the time of five coverage tests', P_max = 0.2/tau)",
            paper=PAPER_TESTS_PER_PRIMITIVE, formula=None, measured=round(fr / T, 4), unit="tests", source=src)
        tab.append(f"| {m} | {ntri} triangles, {W}x{W} | {S:g} | {fr} | {load:.4f} | {load_t:.4f} | {fr / T:.3f} |")
    return ["## The paper's load and maximum performance, in HDL\n",
            f"Coupled HDL runs ({engine}) of random triangles (`reference.random_triangles`, seed {SEED}) of mean "
            "area S_k, where the paper puts the load maximum (\"максимумов загрузки (практически до 100 %) в "
            "окрестности S = Sk\") and the performance limit (\"максимальная производительность соответствует в "
            "среднем времени пяти тестов покрытия\"). Frame cycles end before the read-out.\n",
            "\n".join(tab) + "\n"]


#: the whole matrix in HDL at the paper's 1024² beyond 4x4 (c300, default processor, input FIFO depth
#: REF_DEPTH): Verilator's hierarchical build (the cell verilated once, ``docs/sparse.md``)
LARGE_MATRICES = ("8x8", "16x16")
LARGE_FAST_SKIP = ("slow row: not measured in a fast run (the whole matrix in Verilator at 1024², hierarchical "
                   "build: measured 8x8 12 min, 16x16 26 min, cold, at load 10-30, of them the Verilator build "
                   "473 s and 1,014 s); rasterhw report sparse without --fast measures it")
LARGE_ENGINE_SKIP = ("needs --engine verilator: pysim runs a few thousand cycles a second, too slow for a 1024² "
                     "frame of 64 or 256 processors")


def _large_matrix_hdl_rows(engine: str, *, fast: bool, progress: bool) -> tuple[list[dict], list[str]]:
    """The 8x8 and 16x16 matrices on c300 at 1024² in one Verilator simulation each: frame cycles
    against the golden coupled cycle model, every counter and pixel against the golden models,
    frame / busiest stage ((9)) and R_p from HDL frame time beside (10). Unmeasured (with the
    reason) in a ``fast`` run or on pysim; the formula column is filled either way. No rows on an engine
    that is no HDL simulator (as the other HDL rows)."""

    if engine not in ("pysim", "verilator"):
        return [], []
    W = 1 << M_BITS
    D = REF_DEPTH
    tris = run_geometry(build_scene("c300"), W, W)
    why = LARGE_FAST_SKIP if fast else (None if engine == "verilator" else LARGE_ENGINE_SKIP)
    src = "hdl:verilator"
    out, tab = [], []
    for m in LARGE_MATRICES:
        p = int(m.split("x")[0])
        P = p * p
        n = M_BITS - (p.bit_length() - 1)
        tf = th.stage_times(_formula_frame(np.asarray(tris.xy), n, p), kp_ke=0.0)
        Rp_f = float(tf.sum() / (n * tf.max()))
        r = None
        if why is None:
            from rasterhw.sim.sparse.scene import simulate_coupled

            r = simulate_coupled(tris, m, engine="verilator", fifo_depth=D, progress=progress)
            gfr = sparse_render(tris, (p, p), depth="fixed", per_record=True)
            B_pi = cy.stage_cycles(gfr.stats["windows_per_record"]).sum(axis=1).astype(float)   # (P, n)
            fr = r["frame_cycles"]
            got = {"frame": fr, "diff": fr - r["frame_cycles_golden"], "counters": r["cycle_mismatches"],
                   "pixels": r["mismatches"], "busiest": round(fr / float(B_pi.max()), 4),
                   "Rp": round(float(np.sum(r["tests_per_level_hdl"]) / (n * P * fr)), 4),
                   "Rp_h": round(float(B_pi.sum() / (n * P * fr)), 4)}
            tab.append(f"| {m} | {fr} | {r['frame_cycles_golden']} | {r['stall_cycles']} | {r['cycle_mismatches']} "
                       f"of {r['cycles_compared']} | {r['mismatches']} of {r['pixels_compared']} | {got['busiest']:.4f} | "
                       f"{got['Rp']:.4f} ({got['Rp_h']:.4f}) | {Rp_f:.4f} | {r['build_s']:.1f} | {r['run_s']:.1f} |")
        else:
            got = dict.fromkeys(("frame", "diff", "counters", "pixels", "busiest", "Rp", "Rp_h"))
        q = f"c300 {W}x{W}, {m}, eight-entry inner FIFOs (ours, the default), input FIFO depth {D}, whole matrix in HDL"
        spec = [("FIFO sizing (coupled, HDL)", f"{q}: frame cycles", None, got["frame"], "cycles"),
                ("FIFO sizing (coupled, HDL)", f"{q}: frame cycles, HDL minus the golden coupled cycle model "
                 "(coupled_matrix_vp)", 0, got["diff"], "cycles"),
                ("FIFO sizing (coupled, HDL)", f"{q}: counters differing from the golden coupled cycle model (frame, "
                 "stalls, every FIFO peak, busy and per-level tests)", 0, got["counters"], "counters"),
                ("FIFO sizing (coupled, HDL)", f"{q}: pixels differing from the bit-accurate golden model (of "
                 f"{W * W})", 0, got["pixels"], "pixels"),
                ("(9) / HDL frame time", f"{q}: frame cycles / the busiest stage's busy cycles (tests + header cycles "
                 "of the busiest processor's busiest stage; (9): the pipeline runs at its slowest stage)", 1.0,
                 got["busiest"], "ratio"),
                ("(10) / HDL frame time", f"{q}: R_p from HDL frame time, sum_i B_i / (n P frame cycles), B_i the HDL "
                 "stages' coverage tests (formula: (10) on (1)'s counts, k_p/k_e = 0)", round(Rp_f, 4), got["Rp"], ""),
                ("(10) / HDL frame time", f"{q}: R_p from HDL frame time counting header cycles, sum_i (tests + "
                 "headers)_i / (n P frame cycles) (formula: (10) on (1)'s counts, k_p/k_e = 0)", round(Rp_f, 4),
                 got["Rp_h"], "")]
        out += [make_row(SYSTEM, fig, qty, paper=None, formula=f, measured=v, unit=u, source=src,
                         reason=None if v is not None else why, run=why is None) for fig, qty, f, v, u in spec]
    sec = ["## The 8x8 and 16x16 matrices in HDL at 1024²\n"]
    if tab:
        sec += [f"c300 at {W}², the default processor, input FIFO depth {D}, each matrix one Verilator simulation "
                "(hierarchical build: the cell verilated once; `rasterhw sim sparse --scene c300 --size 1024x1024 "
                f"--matrix M --fifo-depth {D} --engine verilator --json`).\n",
                "| matrix | frame cycles, HDL | golden | broadcast stalls, HDL | counters differing | pixels differing | "
                "frame / busiest stage ((9): 1) | R_p from HDL frame time (with headers) | (10) | build s | run s |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|\n" + "\n".join(tab) + "\n"]
    else:
        sec += [f"Not simulated in this run: {why}.\n"]
    return out, sec


def _load_rows(row, W: int, ntri: int) -> list[str]:
    """R_p of frames of equal-area random triangles near S_k and at 1000 px (the paper's claim of a
    load maximum "практически до 100 %" in the neighbourhood of S = S_k)."""

    tab = ["| matrix | mean area S | R_p measured (model: (5), (10) on golden counts) | R_p formula (10) | "
           "R_p golden, our pipeline (headers, k_p = 0) |", "|---|---|---|---|---|"]
    for k in (2, 3, 4):
        p = 1 << k
        if W // p < 2:
            continue
        for S in (PAPER_S_K[k - 1], 1000.0):
            tris = random_triangles(W, W, ntri, mean_area=S, seed=SEED)
            xy = np.asarray(tris.xy)
            f = sparse_render(tris, (p, p), per_record=True)
            w = f.stats["windows_per_record"]
            n = f.n
            B = cy.stage_cycles(w, kp=3, headers=False).sum(axis=(0, 1)).astype(float)  # k_p/k_e = 3/3
            Rm = float(B.sum() / (n * B.max()))
            Bg = cy.stage_cycles(w).sum(axis=(0, 1)).astype(float)
            Rg = float(Bg.sum() / (n * Bg.max()))
            tf = th.stage_times(_formula_frame(xy, n, p), kp_ke=1.0)
            Rf = float(tf.sum() / (n * tf.max()))
            Sm = float(np.mean(_area_perimeter(xy)[0]))
            near = S < 999
            row("fig. 6b text", f"R_p of a frame of {ntri} random triangles of mean area {Sm:.3g} px "
                f"({'S_k' if near else 'S = 1000'}), {p}x{p}, {W}x{W} (paper: load maximum "
                "'practically up to 100 %' near S_k)", paper=1.0 if near else None, formula=round(Rf, 4),
                measured=round(Rm, 4), unit="", source="model")
            tab.append(f"| {p}x{p} | {Sm:.3g} ({'S_k' if near else '1000'}) | {Rm:.4f} | {Rf:.4f} | {Rg:.4f} |")
    return tab


def _fifo_plot(out_dir: Path, curves: dict, lab: str) -> str:
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    with saved_figure(out_dir / "sparse_fifo.png", figsize=(6, 4), dpi=90) as ax:
        for m, c in curves.items():
            ax.semilogx(FIFO_DEPTHS, c, "o-", base=2, label=m)
        ax.axhline(1.0, color="k", lw=0.8, ls=":")
        ax.set_xlabel("FIFO depth D (records)")
        ax.set_ylabel("frame cycles / unbounded FIFO")
        ax.set_title(f"coupled matrix, {lab} (golden cycle model)", fontsize=9)
        ax.legend()
    return "sparse_fifo.png"


def _coupled_hdl_rows(row, engine: str, progress: bool) -> list[str]:
    """The whole matrix in HDL (``hdl/sparse/matrix.py``, one simulation) at a few FIFO depths: frame
    cycles, stalls and FIFO peaks beside the golden coupled cycle model (``coupled_matrix_vp``), and
    R_p, Q_a, Q_p from the HDL's busy-cycle counters beside formulas (10), (7), (12)."""
    from rasterhw.sim.sparse.scene import simulate_coupled

    if engine == "verilator":
        W, m, depths = 1 << M_BITS, "4x4", (1, 8, 64)
        tris = run_geometry(build_scene("c300"), W, W)
        lab = f"c300 {W}x{W}"
    elif engine == "pysim":  # pysim runs a few k cycles/s: a small frame
        W, m, depths = 32, "2x2", (1, 8)
        tris = random_triangles(W, W, 30, mean_area=40.0, seed=SEED)
        lab = f"30 random triangles of 40 px, {W}x{W}"
    else:
        return [f"## The whole matrix in HDL\n\nNo rows: engine {engine!r} is not supported (pysim or verilator).\n"]
    src = f"hdl:{engine}"
    fig = "FIFO sizing (coupled, HDL)"
    tab = ["| processor | FIFO depth D | frame cycles, HDL | golden cycle model | stall cycles, HDL | golden | "
           "FIFO peak, HDL | golden | counters differing | least / most loaded processor busy / frame |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    # the default processor (eight-entry inner FIFOs) at every depth and the two-entry one beside it at
    # the shallowest and the deepest; the small pysim frame: the default only (the other: golden rows)
    configs = [(who, vpd, depths if key == "eight" else (depths[0], depths[-1])) for key, who, vpd in _VP_CONFIGS]
    every = {}
    for who, vpd, dd in configs:
        runs = every[vpd] = {}
        for D in dd:
            r = simulate_coupled(tris, m, engine=engine, fifo_depth=D, vp_fifo_depth=vpd, progress=progress)
            runs[D] = r
            fr = r["frame_cycles"]
            util = np.array(r["busy"]) / fr
            tab.append(f"| {who} | {D} | {fr} | {r['frame_cycles_golden']} | {r['stall_cycles']} | "
                       f"{r['stall_cycles_golden']} | {r['fifo_peak_max']} | {r['fifo_peak_max_golden']} | "
                       f"{r['cycle_mismatches']} of {r['cycles_compared']} | {util.min():.3f} … {util.max():.3f} |")
            g = r["frame_cycles_golden"]
            for qty, formula, v, unit in (
                    (f"frame cycles of the whole matrix in one simulation, FIFO depth {D}", None, fr, "cycles"),
                    (f"frame cycles, HDL minus the golden coupled cycle model (coupled_matrix_vp: {g}), FIFO depth "
                     f"{D}", 0, fr - g, "cycles"),
                    (f"broadcast stall cycles, FIFO depth {D} (golden cycle model: {r['stall_cycles_golden']})",
                     None, r["stall_cycles"], "cycles"),
                    (f"largest FIFO peak, FIFO depth {D} (golden cycle model: {r['fifo_peak_max_golden']})", None,
                     r["fifo_peak_max"], "entries"),
                    ("counters differing from the golden coupled cycle model (frame, stalls, every FIFO peak, busy "
                     f"and per-level tests; of {r['cycles_compared']}), FIFO depth {D}", 0, r["cycle_mismatches"],
                     "counters"),
                    (f"pixels differing from the bit-accurate golden model (of {r['pixels_compared']}), FIFO depth "
                     f"{D}", 0, r["mismatches"], "pixels")):
                row(fig, f"{lab}, {m}, {who}: {qty}", paper=None, formula=formula, measured=v, unit=unit, source=src)
        row(fig, f"{lab}, {m}, {who}: frame with FIFO depth {dd[0]} / with depth {dd[-1]} (whole matrix in HDL)",
            paper=None, formula=None, measured=round(runs[dd[0]]["frame_cycles"] / runs[dd[-1]]["frame_cycles"], 5),
            unit="ratio", source=src)
    p = int(m.split("x")[0])
    P = p * p
    gfr = sparse_render(tris, (p, p), depth="fixed", per_record=True)
    B_pi = cy.stage_cycles(gfr.stats["windows_per_record"]).sum(axis=1).astype(float)  # (P, n) tests + headers
    T_mono = _mono_stack_cycles(tris)
    # (9) and (10) against HDL time, for every processor run: the frame against its busiest stage
    # (tests + header cycles per stage, summed over records), and the load over the frame
    fr_tab = ["| processor | FIFO depth D | frame / busiest stage's busy cycles ((9): 1) | load, sum B / (n P frame) | "
              "(10) on measured window counts, sum B / (n max B) |", "|---|---|---|---|---|"]
    for who, vpd, dd in configs:
        for D in dd:
            r = every[vpd][D]
            fr = r["frame_cycles"]
            n = r["n"]
            q = f"{lab}, {m}, {who}, FIFO depth {D}"
            ld = float(B_pi.sum() / (n * P * fr))
            ld10 = float(B_pi.sum(axis=0).sum() / (n * B_pi.sum(axis=0).max()))
            row("(9) / HDL frame time", f"{q}: frame cycles / the busiest stage's busy cycles (tests + header "
                "cycles of the busiest processor's busiest stage; (9): the pipeline runs at its slowest stage)",
                paper=None, formula=1.0, measured=round(fr / float(B_pi.max()), 4), unit="ratio", source=src)
            row("(10) / HDL frame time", f"{q}: load R_p from HDL frame time, sum_i B_i / (n P frame cycles) (B_i: "
                "HDL tests per level + header cycles; formula: (10) on measured window counts, sum_i B_i / "
                "(n max_i B_i))", paper=None, formula=round(ld10, 4), measured=round(ld, 4), unit="", source=src)
            fr_tab.append(f"| {who} | {D} | {fr / float(B_pi.max()):.4f} | {ld:.4f} | {ld10:.4f} |")
    runs = every[HDL_FIFO_DEPTH]
    # R_p, Q_a, Q_p at the reference depth (or the deepest run), default processor
    D = REF_DEPTH if REF_DEPTH in runs else depths[-1]
    r = runs[D]
    n = r["n"]
    Bi = np.array(r["tests_per_level_hdl"], dtype=float)   # coverage tests per stage, all processors
    Rp = float(Bi.sum() / (n * Bi.max()))
    Rp_c = float(Bi.sum() / (n * P * r["frame_cycles"]))
    Rp_h = float(B_pi.sum() / (n * P * r["frame_cycles"]))
    m_bits = (tris.width - 1).bit_length()
    fw = _formula_frame(np.asarray(tris.xy), n, p)
    tf = th.stage_times(fw, kp_ke=0.0)
    Rp_f = float(tf.sum() / (n * tf.max()))
    T_mono_tests = float(sparse_render(tris, "1x1", depth="fixed").tests.sum())
    Qa = T_mono_tests / float(Bi.sum())
    fw_mono = _formula_frame(np.asarray(tris.xy), m_bits, 1)
    Qa_f = float(th.total_time(fw_mono, kp_ke=0.0) / (P * th.total_time(fw, kp_ke=0.0)))
    Qp_t = T_mono / (n * P * r["frame_cycles"])
    row("(10) / HDL counts", f"{lab}, {m}: R_p, (10) on measured window counts: sum_i B_i / (n max_i B_i), B_i "
        f"the HDL stages' coverage tests summed over processors, FIFO depth {D} (formula: (10) on (1)'s counts, "
        "k_p/k_e = 0; counts carry no timing)", paper=None, formula=round(Rp_f, 4), measured=round(Rp, 4), unit="",
        source=src)
    row("(10) / HDL frame time", f"{lab}, {m}: R_p from HDL frame time, sum_i B_i / (n P frame cycles), B_i the HDL "
        f"stages' coverage tests, FIFO depth {D} (formula: (10) on (1)'s counts, k_p/k_e = 0)", paper=None,
        formula=round(Rp_f, 4), measured=round(Rp_c, 4), unit="", source=src)
    row("(10) / HDL frame time", f"{lab}, {m}: R_p from HDL frame time counting header cycles, sum_i (tests + "
        f"headers)_i / (n P frame cycles), FIFO depth {D}", paper=None, formula=round(Rp_f, 4),
        measured=round(Rp_h, 4), unit="", source=src)
    row("(7) / HDL counts", f"{lab}, {m}: Q_a, (7) on measured window counts: T_mono / (HDL coverage tests of all "
        "processors) (T_mono: the golden 1x1 search on the full raster; formula (7) on (1)'s counts, k_p/k_e = 0)",
        paper=None, formula=round(Qa_f, 4), measured=round(Qa, 4), unit="", source=src)
    row("(12) / HDL counts", f"{lab}, {m}: Q_p, (12) on measured window counts: Q_a R_p from the HDL's test counts",
        paper=None, formula=round(Qa_f * Rp_f, 4), measured=round(Qa * Rp, 4), unit="", source=src)
    row("(12) / HDL frame time", f"{lab}, {m}: Q_p from HDL frame time, T_so / (n P frame cycles), T_so the "
        f"monoprocessor-with-stack's cycles on the full raster (golden stack cycle model: {T_mono:.0f}), FIFO depth "
        f"{D} (formula: (12) on (1)'s counts)", paper=None, formula=round(Qa_f * Rp_f, 4), measured=round(Qp_t, 4),
        unit="", source=src)
    return ["## The whole matrix in HDL (one simulation)\n",
            f"`rasterhw sim sparse` (coupled, {engine}) run inside this report: {lab}, {m}, the input FIFOs limited "
            "at run time to D entries (one build), the geometry processor offering a record every cycle (ours). "
            "Every counter of the HDL is compared with the golden coupled cycle model (`coupled_matrix_vp`, "
            "processors as the HDL video processor's cycle model). Two processors, both ours (the paper gives no "
            "buffer size: a \"sufficient\" input FIFO, \"достаточном объеме FIFO\", and the micro-pipeline "
            "referred to its [3]): eight-entry FIFOs between the levels (the default of `rasterhw sim sparse`, "
            "the depth that reproduces (9) and (10), below) and two-entry buffers (`--vp-fifo-depth 2`). R_p, "
            "Q_a, Q_p below are the default processor's.\n",
            "\n".join(tab) + "\n",
            f"At D = {D}: R_p from HDL frame time {Rp_c:.4f} ({Rp_h:.4f} counting header cycles), Q_p from HDL "
            f"frame time {Qp_t:.4f}; on the measured window counts R_p {Rp:.4f}, Q_a {Qa:.4f}, Q_p {Qa * Rp:.4f}; "
            f"formulas (10) {Rp_f:.4f}, (7) {Qa_f:.4f}, (12) {Qa_f * Rp_f:.4f}.\n",
            "Formulas (9) and (10) against HDL time, each processor: (9) says the pipeline runs at its slowest "
            "stage (frame / busiest stage = 1), (10) gives the load from the stages' work alone; the HDL frame "
            "shows what the inner buffers cost.\n", "\n".join(fr_tab) + "\n"]
