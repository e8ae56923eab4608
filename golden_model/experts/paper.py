"""Every figure of seed 000 (EXPERTS) that our code and reports use, each with the paper's words
and where they stand in ``shared/seeds/000_*.txt``.

Nothing else under ``golden_model/`` or ``sim/`` defines a paper value for this machine.
:data:`QUOTES` maps each name to (location, the paper's words). A value here is one the paper
prints; what follows from it by arithmetic is a ``formula`` in the reports, never a ``paper`` cell:
our reading of Q_p's 31607 sqrt(Fr) as 887 sqrt(Fr) span cull + 30720 sqrt(Fr) depth search
(``docs/experts.md``, cost model) is ours and lives in ``cost.py``; the reciprocal ROM's size, the
intensity width 7 and the other decisions where the paper is silent live in ``formats.py`` and
``slp_setup.py`` with the paper's words they rest on.
"""

from __future__ import annotations

__all__ = ["PAPER_T21", "PAPER_T22", "PAPER_T22_SEGMENTS", "PAPER_FRAME", "PAPER_PIXEL_BITS", "PAPER_HUE_BITS",
           "PAPER_HUE_CHANNEL_BITS", "PAPER_INTENSITY_BITS", "PAPER_WORD_BITS", "PAPER_DC", "PAPER_COST",
           "PAPER_FR", "PAPER_SLPS", "PAPER_PXPS_PER_SLP", "PAPER_PXPS", "PAPER_REALTIME_FACES",
           "PAPER_PXPS_PER_SLP_BALANCED", "PAPER_SLP", "PAPER_PXP", "QUOTES"]

#: table 2.1: the increase (%) of the work with A.J. (c) over none, by the solid's number of line segments
PAPER_T21 = {"5": 4.4, "9": 5.0, "15": 6.4, "20": 12.4}
#: table 2.2: the work with A.J. on line segments, the work without = 1, method (b) and (c)
PAPER_T22 = {"b": 1.15, "c": 3.35}
#: table 2.2: the number of line segments
PAPER_T22_SEGMENTS = 8
#: the logical frame buffer, 512 x 512 pixels (also x = y = 512 of the cost model)
PAPER_FRAME = 512
#: a pixel is 16 bits: hue 9 bits (red, green, blue 3 bits each) and intensity 4 bits
PAPER_PIXEL_BITS = 16
PAPER_HUE_BITS = 9
PAPER_HUE_CHANNEL_BITS = 3
PAPER_INTENSITY_BITS = 4
#: the SLP's and PXP's basic operation width, 16 bits
PAPER_WORD_BITS = 16
#: the depth complexity the cost model's totals take
PAPER_DC = 3
#: the cost model's printed totals at Dc = 3, x = y = 512:
#: Q_seq = 4 Fr + 3.46 Fr sqrt(Fr) + 32500 sqrt(Fr); Q_s = (4 Fr + 3.46 Fr sqrt(Fr) + 893 sqrt(Fr)) / Sn;
#: Q_p = 31607 sqrt(Fr) / (Sn Pn)
PAPER_COST = {"fr": 4, "fr_sqrt_fr": 3.46, "seq_sqrt_fr": 32500, "slp_sqrt_fr": 893, "pxp_sqrt_fr": 31607}
#: fig. 4.1's numbers of relevant faces
PAPER_FR = (1000, 2000)
#: the configuration that renders about 1,000 faces in real time: 8 SLPs, 8 PXPs each, 64 in all
PAPER_SLPS = 8
PAPER_PXPS_PER_SLP = 8
PAPER_PXPS = 64
PAPER_REALTIME_FACES = 1000
#: fig. 4.1: 4 to 8 PXPs per SLP suit
PAPER_PXPS_PER_SLP_BALANCED = (4, 8)
#: the stages the cost model prices for the SLP (i-iii) and the PXP (iv, v), by our stage names
PAPER_SLP = ("y_sort", "x_merge", "l_sort")
PAPER_PXP = ("span_cull", "depth_search")

QUOTES: dict[str, tuple[str, str]] = {
    "PAPER_T21": ("2.4, table 2.1", "A.J.を施さない場合の処理量に対する増加% 線分の数 / 三角錐 4.4 5 / 四角柱(類1) 5.0 9 / "
                  "八角錐 6.4 15 / カウ-ハーン(類2) 12.4 20"),
    "PAPER_T22": ("2.4, table 2.2", "(b)の方法での処理量 (c)の方法での処理量 / 8 1.15 (写真3) 3.35 (写真4) / "
                  "A.J.を施さない場合の処理量を1とする"),
    "PAPER_T22_SEGMENTS": ("2.4, table 2.2", "線分の数 (b)の方法での処理量 (c)の方法での処理量 / 8 1.15"),
    "PAPER_FRAME": ("3.2", "論理的な意味でのFBは、 512×512 個の画素で構成する"),
    "PAPER_PIXEL_BITS": ("3.2", "各画素は16ビットのデータとして表現可る"),
    "PAPER_HUE_BITS": ("3.2", "16ビットの内訳は、色相9ビット、輝度4ビットである"),
    "PAPER_HUE_CHANNEL_BITS": ("3.2", "色相はさらに赤、緑、青 それぞれ3ビットずつから成る"),
    "PAPER_INTENSITY_BITS": ("3.2", "16ビットの内訳は、色相9ビット、輝度4ビットである"),
    "PAPER_WORD_BITS": ("3.2", "EXPERTSの内部データ幅、即ち、SLP、PXPの基本演算データ幅は16ビットである"),
    "PAPER_DC": ("4", "ここで、Dc=3, x=y=512 とおくと"),
    "PAPER_COST": ("4", r"Q_{seg} = 4Fr + 3.46Fr \cdot \sqrt{Fr} + 32500\sqrt{Fr} ... "
                   r"Q_s = \frac{1}{S_n} \cdot (4Fr + 3.46Fr \cdot \sqrt{Fr} + 893\sqrt{Fr}) ... "
                   r"Q_p = \frac{1}{(S_n \cdot P_n)} \cdot (31607 \cdot \sqrt{Fr})"),
    "PAPER_FR": ("4, fig. 4.1", "グラフは表示面数 F_r が 1000 面、及び 2000 面の場合に针对したものである"),
    "PAPER_SLPS": ("5", "SLP 系 8 台、各 SLP 系に PXP 8 台(総計 64 台)の構成で"),
    "PAPER_PXPS_PER_SLP": ("5", "SLP 系 8 台、各 SLP 系に PXP 8 台(総計 64 台)の構成で"),
    "PAPER_PXPS": ("5", "(総計 64 台)"),
    "PAPER_REALTIME_FACES": ("5", "約 1,000 面から構成される三次元图形の実時間表示処理が可能である"),
    "PAPER_PXPS_PER_SLP_BALANCED": ("4, fig. 4.1", "SLP 1 台に対する PXP の個数は 4 ～ 8 台が適していると考えられる"),
    "PAPER_SLP": ("4 i)-iii)", "《Y-sort》 ... 《X-merge》 ... 《L-sort》"),
    "PAPER_PXP": ("4 iv), v)", "《span cull》 ... 《depth search》"),
}
