"""Every figure of seed 003 (ZB/M) that our code and reports use, each with the paper's words
and where they stand in ``shared/seeds/003_*.txt``.

Nothing else under ``golden_model/`` or ``sim/`` defines a paper value for this machine.
:data:`QUOTES` maps each name to (location, the paper's words). A value here is one the paper
prints; what follows from it by arithmetic (148 = 2 x 74 cycles for two skewed units, a chain's
speed-up of N over one unit, 49,152 = 48 x 1024 bits) is a ``formula`` in the reports, never a
``paper`` cell.
"""

from __future__ import annotations

__all__ = ["PAPER_CLOCK_HZ", "PAPER_CYCLES", "PAPER_EDGE_PAIRS_PER_POLYGON", "PAPER_GATES", "PAPER_I860S_PER_UNIT",
           "PAPER_I860_CLOCK_HZ", "PAPER_KPOLYS", "PAPER_LEN_CHIP", "PAPER_RAM_KBITS", "PAPER_SKEW_WAIT",
           "PAPER_TABLE2", "PAPER_TEST_POLYGONS", "PAPER_UNITS", "PAPER_UNITS_RATE", "PAPER_C_OVER_ASM", "QUOTES"]

#: condition 3: the ZB/M's input clock
PAPER_CLOCK_HZ = 25e6
#: condition 1: every polygon becomes two edge pairs
PAPER_EDGE_PAIRS_PER_POLYGON = 2
#: condition 7: half the time waiting on the neighbouring ZB/M ("半分の時間は待ち状態")
PAPER_SKEW_WAIT = 0.5
#: cycles per edge pair by interleave (sec. 6.1's arithmetic: 9 + (len + 8) x 5; "8 インタリーブ以上" = 54)
PAPER_CYCLES = {1: 74, 2: 64, 4: 59, 8: 54, 16: 54}
#: "the average segment length per ZB/M" by interleave (sec. 6.1)
PAPER_LEN_CHIP = {1: 5, 2: 3, 4: 2, 8: 1, 16: 1}
#: table 1, K polygons/s per unit
PAPER_KPOLYS = {1: 84.5, 2: 97.7, 4: 105.9, 8: 115.8, 16: 115.8}
#: about 64 units in parallel ...
PAPER_UNITS = 64
#: ... give 7.4 M textured polygons/s
PAPER_UNITS_RATE = 7.4e6
#: table 2: processors N -> (C seconds, assembler seconds, K polygons/s per processor) for 5,760 / N
#: polygons on one i860XR at 33.3 MHz
PAPER_TABLE2 = {4: (0.107, 0.090, 16.0), 8: (0.054, 0.050, 14.4), 12: (0.037, 0.033, 14.5),
                16: (0.029, 0.025, 14.4)}
#: table 2's test data
PAPER_TEST_POLYGONS = 5760
#: the board table 2 was measured on
PAPER_I860_CLOCK_HZ = 33.3e6
#: the assembler version "about 1.25 times" faster
PAPER_C_OVER_ASM = 1.25
#: "i860 プロセッサ 8 個でバランスする"
PAPER_I860S_PER_UNIT = 8
#: sec. 7: logic about 27,000 gates
PAPER_GATES = 27_000
#: sec. 7: RAM 49 Kbits, as printed (49,152 = 48 x 1024 is our reading, a formula)
PAPER_RAM_KBITS = 49

QUOTES: dict[str, tuple[str, str]] = {
    "PAPER_CLOCK_HZ": ("6.1 condition 3", "ZB/M の入力クロックは 25MHz"),
    "PAPER_EDGE_PAIRS_PER_POLYGON": ("6.1 condition 1", "前処理で各ポリゴンは 2 エッジペアに展開される"),
    "PAPER_SKEW_WAIT": ("6.1 condition 7", "隣の ZB/M とのタイミングずれにより半分の時間は待ち状態と考える"),
    "PAPER_CYCLES": ("6.1", r"1 エッジペアの処理サイクル数は $9 + 9 \times 5 = 54$ Cycles となる ... "
                     r"$9 + 10 \times 5 = 59$ サイクル ... $9 + 11 \times 5 = 64$ サイクル ... "
                     r"$9+13\times 5 = 74$ サイクル ... 8 インタリープ以上では"),
    "PAPER_LEN_CHIP": ("6.1", "1 個の ZB/M 当たりの平均セグメント長が 1 / は 2 / は 3 / は 5 となり"),
    "PAPER_KPOLYS": ("table 1", r"処理能力 84.5 97.7 105.9 115.8 115.8 / 単位: $K \text{Polygons/sec}$"),
    "PAPER_UNITS": ("abstract, 7", "このユニットを 64 ユニット程度並列動作させることにより"),
    "PAPER_UNITS_RATE": ("abstract, 7", r"テクスチャ付ポリゴン処理能力 $7.4M \text{Polygons/sec}$"),
    "PAPER_TABLE2": ("table 2", r"4 プロセッサ 0.107sec 0.090sec $16.0K \text{Polys/sec}$ / "
                     r"8 プロセッサ 0.054sec 0.050sec $14.4K \text{Polys/sec}$ / "
                     r"12 プロセッサ 0.037sec 0.033sec $14.5K \text{Polys/sec}$ / "
                     r"16 プロセッサ 0.029sec 0.025sec $14.4K \text{Polys/sec}$"),
    "PAPER_TEST_POLYGONS": ("6.2", "テストデータとしては 5,760 Polygon のデータを 4,8,12,16 分割して用い"),
    "PAPER_I860_CLOCK_HZ": ("6.2", "i860 プロセッサを用いた市販のボード (i860XR 33.3MHz) を利用し"),
    "PAPER_C_OVER_ASM": ("6.2", "アセンブラー化した場合のポリゴンの生成速度は約 1.25 倍程度高速化されており"),
    "PAPER_I860S_PER_UNIT": ("6.2", "i860 プロセッサ 8 個でバランスするという計算になる"),
    "PAPER_GATES": ("7", "ロジック部約 27,000 ゲート"),
    "PAPER_RAM_KBITS": ("7", "RAM 部 49Kbits で実現できる見込みである"),
}
