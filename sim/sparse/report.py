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
from rasterhw.golden_model.sparse import montecarlo as mc
from rasterhw.golden_model.sparse import theory as th
from rasterhw.sim.report import make_row

SYSTEM = "sparse"
M_BITS = 10  # the paper's full raster: 2**10 x 2**10
KS = (1, 2, 3, 4)
SEED = 2002
#: areas at which the Monte-Carlo counts are measured for figs. 3, 5, 6
S_GRID = (0.1, 0.3, 1.0, 1.8, 3.0, 6.0, 10.0, 23.3, 40.0, 100.0, 157.0, 300.0, 1000.0)


def _counts(S: float, n: int, p: int, M: int, test: str = "exact", seed: int = SEED) -> mc.MCResult:
    poly, off = mc.rectangles(S, M, seed=seed)
    return mc.level_counts(poly, off, n, p, test=test)


def _fmt_ci(r: mc.MCResult, i: int) -> str:
    return f"{r.mean[i]:.4g} ± {r.half95[i]:.2g}"


def rows(*, engine: str = "pysim", progress: bool = False, out_dir: Path = Path("docs/reproduction"),
         samples: int = 20000, scenes: tuple[str, ...] = ("c300", "sp27"), s_grid: tuple[float, ...] = S_GRID,
         **known):
    """Rows and markdown sections of the sparse-raster report (see the module docstring)."""
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
    for k, paper in zip(KS, th.PAPER_S_K, strict=True):
        f = th.s_k(k)
        s_ex = mc.s_k_measured(k, m=M_BITS, M=M, seed=SEED, test="exact")
        s_ed = mc.s_k_measured(k, m=M_BITS, M=M, seed=SEED, test="edges")
        sk_meas[k] = (s_ex, s_ed)
        row("text after (4)", f"S_{k}: area with w_n = 1, {1 << k}x{1 << k}, 5:1 rectangles, exact test "
            f"(MC {M}, 95 % [{s_ex[1]:.3g}, {s_ex[2]:.3g}])", paper=paper, formula=round(f, 4),
            measured=round(s_ex[0], 4), unit="px", source="golden")
        row("text after (4)", f"S_{k}, edges-only test (MC {M}, 95 % [{s_ed[1]:.3g}, {s_ed[2]:.3g}])",
            paper=paper, formula=round(f, 4), measured=round(s_ed[0], 4), unit="px", source="golden")

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
        from rasterhw.golden_model.pipeline import run_geometry
        from rasterhw.golden_model.scenes import build_scene
        from rasterhw.golden_model.sparse.search import sparse_render

        tris = run_geometry(build_scene(name), 512, 512)
        xy = np.asarray(tris.xy)
        n, p = 7, 4  # 512 = 4 * 2**7
        poly, off = mc.triangles_from_scene(xy, M, seed=SEED)
        r = mc.level_counts(poly, off, n, p, test="exact")
        e1, e2 = poly[:, 1] - poly[:, 0], poly[:, 2] - poly[:, 0]
        S_t = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        U_t = np.linalg.norm(poly - np.roll(poly, -1, 1), axis=2).sum(1)
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
        xs = xy  # formula on the frame's own triangles
        e1, e2 = xs[:, 1] - xs[:, 0], xs[:, 2] - xs[:, 0]
        Sf = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        good = Sf > 1e-6
        Uf = np.linalg.norm(xs - np.roll(xs, -1, 1), axis=2).sum(1)
        ff = np.zeros(n + 1)
        for s, u in zip(Sf[good], Uf[good], strict=True):
            ff += th.windows(float(s), n, p, L=float(u / (2 * math.sqrt(math.pi * s))))
        ff /= good.sum()
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
                row("fig. 6a text", f"limiting level at S={S:g}, {1 << k}x{1 << k} (n = {n}; paper: first level "
                    f"for S_f ≪ pq, last for S_f ≫ pq)", paper=1 if S < 1 else n, formula=lf, measured=lm,
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
               "\n".join(f"| {k} | {th.PAPER_S_K[k - 1]:g} | {th.s_k(k):.4g} | {e[0]:.4g} [{e[1]:.4g}, {e[2]:.4g}] | "
                         f"{d[0]:.4g} [{d[1]:.4g}, {d[2]:.4g}] |" for k, (e, d) in sk_meas.items()) + "\n")
    sec.append("## Limiting level in each regime\n")
    sec.append("\n".join(reg) + "\n\nFrom the formula on a fine grid (S = 0.1 … 1000): " + "; ".join(lim_ranges) + ".\n")
    sec.extend(hdl_sec)
    sec.append("## Figures\n")
    sec.append("\n".join(f"![{t}]({fn})" for t, fn in plots) + "\n")
    return out, sec


def _formula_frame(xy: np.ndarray, n: int, p: int) -> np.ndarray:
    """Formula (1) summed over a frame's triangles (each with its own S and L): (n + 1,)."""
    e1, e2 = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
    S = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    U = np.linalg.norm(xy - np.roll(xy, -1, 1), axis=2).sum(1)
    good = S > 1e-6
    tot = np.zeros(n + 1)
    for s, u in zip(S[good], U[good], strict=True):
        tot += th.windows(float(s), n, p, L=float(u / (2 * math.sqrt(math.pi * s))))
    return tot


def _hdl_rows(row, engine: str, progress: bool, hdl_scene=None) -> list[str]:
    """Busy cycles per stage of the HDL video processors (τ = one cycle per coverage test)."""
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.reference import random_triangles
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.sim.sparse.sim import simulate_tris

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
    return ["## HDL cycles\n",
            f"`rasterhw sim sparse` run inside this report ({engine}): {label}, 4x4, every processor; "
            f"{r['cycles']} cycles for the slowest processor, {r['sim_cycles']} cycles simulated in all at "
            f"{r['cycles_per_s']} cycles/s; busy cycles (coverage tests) per level summed over processors: "
            f"{r['tests_per_level_hdl']}. A stage makes one coverage test per busy cycle (τ = 1 cycle) and takes "
            "the next window in the cycle of its last test; the frame still takes a little more than its busiest "
            "stage's tests: a triangle's header costs one cycle at every level where it has survivors, and a "
            "full FIFO stalls the stage before it.\n"]


def _plots(out_dir: Path, spr, mono, Sg, S_GRID):  # noqa: N803
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    files = []
    Sm = np.array(S_GRID)
    # fig. 3: w_i(S) per k
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
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
    fig.tight_layout()
    fig.savefig(out_dir / "sparse_fig3.png", dpi=90)
    plt.close(fig)
    files.append(("fig. 3", "sparse_fig3.png"))
    # fig. 4: alpha_i
    fig, ax = plt.subplots(figsize=(6, 4))
    for k in KS:
        n = M_BITS - k
        i = np.arange(1, n + 1)
        ax.plot(i, th.alpha_i(i, n, 1 << k), "o-", label=f"{1 << k}x{1 << k}")
    ax.set_xlabel("level i")
    ax.set_ylabel("alpha_i")
    ax.set_title("fig. 4: relative window size (2), alpha = 2")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out_dir / "sparse_fig4.png", dpi=90)
    plt.close(fig)
    files.append(("fig. 4", "sparse_fig4.png"))
    # figs. 5, 6
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for k in KS:
        n, p = M_BITS - k, 1 << k
        w = th.windows(Sg, n, p)
        c = f"C{k - 1}"
        wm = [spr[k][S].mean for S in S_GRID]
        wmo = [mono[S].mean for S in S_GRID]
        axes[0, 0].loglog(Sg, th.perf_stack(w), c, label=f"{p}x{p}")
        axes[0, 0].plot(Sm, [float(th.perf_stack(x)) for x in wm], "o", ms=3, color=c)
        axes[0, 1].semilogx(Sg, th.q_algorithm(Sg, M_BITS, k), c, label=f"{p}x{p}")
        axes[0, 1].plot(Sm, [float(th.total_time(b) / (p * p * th.total_time(a))) for a, b in zip(wm, wmo, strict=True)],
                        "o", ms=3, color=c)
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
    fig.suptitle("lines: formulas (1)-(12); dots: the same formulas on Monte-Carlo window counts")
    fig.tight_layout()
    fig.savefig(out_dir / "sparse_fig5_6.png", dpi=90)
    plt.close(fig)
    files.append(("figs. 5-6", "sparse_fig5_6.png"))
    return files
