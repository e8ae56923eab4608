"""The compiled fast path of the span PXP's cycle model (numba), beside its specification.

:mod:`.span_cycles` is the specification: :func:`~.span_cycles.resolve` walks one line of one range
in plain Python (the span's cull, the entering candidates, the depth search with its halvings,
every cycle counted by step). This module gives the same results, bit for bit, for the scene runs
(``sim/experts/pxp_jobs.py: span_job_list``, ``rasterhw sim pxp``), where the Python walk was
~2 of the ~4 CPU-s of ``sim pxp --scene experts-1000 --sn 8 --pn 8``:

* :func:`resolve` / :func:`line_job`: the same walk in one compiled loop (:func:`_resolve`), the
  line's segments held as arrays (xl, xr, zl, dzdx, addr); every step's count and every pixel's
  visible position equal the specification's (``tests/experts/test_span_cycles_fast.py`` holds
  them equal on whole frames, with and without A.J.).
* :func:`line_asl`: the ASB records built column by column (not one ``asb_record`` call each), the
  last line's kept (a scene run asks for the same line once per PXP range: at ``--pn 8`` it built
  the same records 8 times); :func:`dmm_line`: the block lists' walk (``slp_run.block_lists``)
  compiled (``span_cycles_kernel.block_lists``).

A ``resolver`` other than the span PXP's (``coherent.resolve``) runs the specification's
:func:`~.span_cycles.line_job`. Where numba cannot be loaded, :data:`ENGINE` is ``"python"`` and the
specification runs (one line on stderr, :class:`rasterhw.golden_model.fastpath.FastPath`).
"""

from __future__ import annotations

import weakref

import numpy as np
from rasterhw.golden_model.experts import span_cycles as spec
from rasterhw.golden_model.experts.formats import ADDR_BITS, DZ_FRAC, X_FRAC, Z_BITS
from rasterhw.golden_model.experts.model import ExpertsFrame
from rasterhw.golden_model.experts.pxp_cycles import guarded
from rasterhw.golden_model.fastpath import FastPath

__all__ = ["ENGINE_ENV", "NO_PTR", "choose_engine", "dmm_line", "line_asl", "line_job", "resolve"]

NO_PTR = spec.NO_PTR

#: Environment variable choosing the engine when a call does not: ``python`` (the specification,
#: :mod:`.span_cycles`), ``numba`` (the compiled loop; an error where numba cannot load), or
#: ``auto`` / unset (numba where it loads, else Python with one line on stderr).
ENGINE_ENV = "RASTERHW_SPANCYCLES"
_FAST = FastPath("rasterhw.golden_model.experts.span_cycles_kernel", env=ENGINE_ENV, spec="python",
                 fallback="the span PXP's cycle model runs its Python specification (same cycles, slower)")

_last_asl: list = [None, None, None]   # (weak ref to the frame, y, (segs, ids))
_last_arr: list = [None, None]         # (segs list, its arrays)


def choose_engine(engine: str | None = None) -> str:
    """``"numba"`` or ``"python"``: the engine that runs for ``engine`` (``None`` = :data:`ENGINE_ENV`)."""
    return _FAST.choose(engine)


def line_asl(fr: ExpertsFrame, y: int) -> tuple[list[dict], np.ndarray]:
    """:func:`.span_cycles.line_asl`, the records built column by column, the last line's result
    kept (the same list: do not change it)."""
    ref, yy, hit = _last_asl
    if ref is not None and ref() is fr and yy == y:
        return hit
    if fr.model != "bit":
        return spec.line_asl(fr, y)              # the specification's error
    rec, st = fr.records, fr.setup
    if st.n >= (1 << ADDR_BITS) - 1 or (st.n and int(st.poly.max()) >= (1 << ADDR_BITS) - 1):
        return spec.line_asl(fr, y)
    sel = np.flatnonzero(rec.row == y)
    sel = sel[np.lexsort((rec.tri[sel], rec.xl[sel]))]
    t = rec.tri[sel]
    h = st.hue[t].astype(np.int64)
    cols = {"xl": rec.xl[sel], "xr": rec.xr[sel], "zl": rec.zl[sel], "il": rec.il[sel], "dzdx": st.dzdx[t],
            "didx": st.didx[t], "hue": (h[:, 0] << 6) | (h[:, 1] << 3) | h[:, 2], "addr": t, "poly": st.poly[t],
            "sl": rec.sl[sel], "ql": rec.ql[sel], "sr": rec.sr[sel], "qr": rec.qr[sel]}
    names = tuple(cols)
    segs = [dict(zip(names, row, strict=True)) for row in zip(*(np.asarray(c).tolist() for c in cols.values()),
                                                                 strict=True)]
    hit = (segs, sel)
    _last_asl[:] = [weakref.ref(fr), y, hit]
    return hit


def dmm_line(fr: ExpertsFrame, y: int, bounds, *, engine: str | None = None) -> tuple[list[dict], list[int], list[list[int]]]:
    """:func:`.span_cycles.dmm_line` with :func:`line_asl`'s records and the block lists' walk
    compiled."""
    segs, ids = line_asl(fr, y)
    if len(segs) > spec.DMM_DEPTH or choose_engine(engine) == "python":
        return spec.dmm_line(fr, y, bounds)      # (and the specification's error)
    b = np.asarray(bounds, dtype=np.int64)
    guard = 1 if fr.aj == "c" else 0
    glo = np.maximum(b[:-1] - guard, 0)
    ghi = np.minimum(b[1:] + guard, fr.width)
    live = (ghi > glo) & (b[1:] > b[:-1])
    lead, rows = _FAST.module().block_lists(fr.records.c0[ids].astype(np.int64), fr.records.c1[ids].astype(np.int64),
                                            glo, ghi, live)
    buckets: list[list[int]] = [[] for _ in range(len(glo))]
    for k, pos in rows.tolist():
        buckets[k].append(pos)
    return segs, [NO_PTR if v < 0 else v for v in lead.tolist()], buckets


def _arrays(segs: list[dict]) -> np.ndarray:
    """(5, n) int64: xl, xr, zl, dzdx, addr of every segment (kept for the list :func:`line_asl`
    last returned; any other list is read every call)."""
    kept, a = _last_arr
    if kept is segs and _last_asl[2] is not None and _last_asl[2][0] is segs:
        return a
    a = np.array([[s["xl"], s["xr"], s["zl"], s["dzdx"], s["addr"]] for s in segs], np.int64).reshape(-1, 5).T.copy()
    _last_arr[:] = [segs, a]
    return a


def resolve(segs: list[dict], bucket: list[int], lead: int, glo: int, ghi: int, *,
            engine: str | None = None) -> tuple[dict, list[int]]:
    """:func:`.span_cycles.resolve`: cycles per step and the visible ASL position of every pixel."""
    if choose_engine(engine) == "python":
        return spec.resolve(segs, bucket, lead, glo, ghi)
    cyc, vis = _FAST.module().resolve(_arrays(segs), np.asarray(bucket, np.int64), int(lead), int(glo), int(ghi),
                                      X_FRAC, DZ_FRAC, Z_BITS)
    return dict(zip(spec.STEPS, cyc.tolist(), strict=True)), vis.tolist()


def line_job(segs: list[dict], bucket: list[int], lead: int, lo: int, hi: int, *, aj: str, width: int,
             resolver=None, paper=None, engine: str | None = None) -> dict:
    """:func:`.span_cycles.line_job` with the compiled :func:`resolve` (another ``resolver``: the
    specification's)."""
    if resolver is not None or choose_engine(engine) == "python":
        return spec.line_job(segs, bucket, lead, lo, hi, aj=aj, width=width, resolver=resolver, paper=paper)
    glo, ghi = guarded(lo, hi, width, aj)
    cyc, vis = resolve(segs, bucket, lead, glo, ghi, engine="numba")
    drawn = int((np.asarray(vis) >= 0).sum())
    return {"words": len(segs) + len(bucket) + 1, "resolve": sum(cyc.values()), "steps": cyc,
            "drain": spec.span_drain_cycles(vis, lo, hi, aj=aj, width=width),
            "paper_drain": spec.paper_drain(vis, segs, lo, hi, width=width) if aj == "c" else None,
            "paper_extra": spec.paper_resolve(cyc, drawn), "drawn": drawn,
            "visible": vis[lo - glo:lo - glo + (hi - lo)]}
