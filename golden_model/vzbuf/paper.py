"""Every figure of the vector Z-buffer paper (seed 001) the reports and flows use, with its place in
the seed: tables 1-7 as data (``paper_tables.csv`` beside this module, loaded here) and the
figures of the text.

Read from ``shared/vzbuf_tables.md`` (the cleaned reading) and checked cell by cell against the
seed; a cell the OCR corrupted is corrected from the paper's own identities (totals = sums of
stages, pixels/s = pixels / VP200 total, area = pixels / polygons) and listed in
:data:`CORRECTED`. ``None`` = lost in the OCR. Times in ms.
"""

from __future__ import annotations

import csv
from importlib import resources

__all__ = ["COLS", "COLUMN", "CORRECTED", "QUOTES", "RATES", "RUNS", "SLIST_SPEEDUP_AT_MOST", "SP8_EMPTY_LINE_FRACTION",
           "T1", "T2", "T2_RATE", "T3", "T3_RATE", "T4", "T4_RATE", "T5", "T5_RATE", "T6", "T7", "TABLES", "VP200_T5_C300_FRAGMENTS_PER_S",
           "VP200_T5_C300_MS", "VTIME"]

#: the paper's name of each modelled machine (its tables' row labels)
COLUMN = {"scalar": "scalar", "vp100": "VP100", "vp200": "VP200"}
COLS = ("c300", "c250", "c200", "c150", "c100", "c50", "sp27", "sp5", "sp8")


def _cell(text: str) -> int | float | None:
    return None if text == "" else float(text) if "." in text else int(text)


def _load() -> dict:
    """``paper_tables.csv``, one line per table row: ``kind`` (``attributes`` = table 1,
    ``time`` = a stage of a timing table, ``vectorisation rate``, ``vector time``), ``table``,
    ``machine``, ``row`` (the stage), then a cell per column of :data:`COLS`.
    Returns ``{kind: {table: {machine: {row: {column: value}}}}}``."""
    out: dict = {}
    with resources.files(__package__).joinpath("paper_tables.csv").open(encoding="utf-8") as f:
        for r in csv.DictReader(f):
            cells = {c: _cell(r[c]) for c in COLS}
            out.setdefault(r["kind"], {}).setdefault(r["table"], {}).setdefault(r["machine"], {})[r["row"]] = cells
    return out


_TABLES = _load()
T1 = _TABLES["attributes"]["table 1"][""]
# stage lists per table and machine: {machine: {stage: row}}
T2, T3, T4, T5, T6, T7 = (_TABLES["time"][f"table {i}"] for i in range(2, 8))
# vectorisation rate (%) per table and machine: {machine: row}
T2_RATE, T3_RATE, T4_RATE, T5_RATE = ({m: v[""] for m, v in _TABLES["vectorisation rate"][f"table {i}"].items()}
                                      for i in range(2, 6))
#: "ベクトル処理時間" (time the vector unit was used, 3.3 ③), ms; tables 4/5 give c300..sp5
VTIME = {t: {m: v[""] for m, v in ms.items()} for t, ms in _TABLES["vector time"].items()}

TABLES = {"table 2": T2, "table 3": T3, "table 4": T4, "table 5": T5, "table 6": T6, "table 7": T7}
RATES = {"table 2": T2_RATE, "table 3": T3_RATE, "table 4": T4_RATE, "table 5": T5_RATE}
#: which algorithm / shadow method each timing table ran
RUNS = {"table 2": (1, "none"), "table 3": (2, "none"), "table 4": (1, "polygons"), "table 5": (2, "polygons"),
        "table 6": (1, "map"), "table 7": (2, "map")}

CORRECTED = {
    ("table 1", "processed polygons", "c200"): "583 printed; 80274 / 135.4 = 593",
    ("table 1", "processed polygons", "c100"): "288 printed; 42777 / 143.5 = 298",
    ("table 2", "scalar 1", "c250"): "188 printed (168 in an earlier reading); 787 - 474 - 144 = 169",
    ("table 3", "VP100 2", "sp8"): "107 printed; 290 - 40 - 83 = 167",
    ("table 4", "VP100/VP200 columns", "all"): "header lists c250..sp8 but the 8 values are c300..sp5",
    ("table 5", "VP200 total", "c100"): "769 printed; 42 + 94 + 543 + 110 = 789",
    ("table 6", "scalar 2", "all"): "8 shifted values printed; stage 2 = total - 1 - 3 - 4",
    ("table 7", "scalar 1", "c100"): "700 printed; 3141 - 860 - 1325 - 137 = 819",
}
#: the paper's throughput claim behind the benchmark: table 5, VP200, c300
VP200_T5_C300_MS = 2059
VP200_T5_C300_FRAGMENTS_PER_S = 843730
#: 3.2 note on table 1: "sp8は表示図形のスクリーンに占める割合が小さく、全スクリーンラインの約30%ではデータがない"
#: (sp8 covers little of the screen: about 30 % of all scan lines hold no data)
SP8_EMPTY_LINE_FRACTION = 0.30
#: 4.1 2)(ii): "slistの更新処理はベクトル化されるが…処理速度の向上は高々4倍にとどまる" (the s-list update
#: vectorises, but its speed-up stays at most 4 times)
SLIST_SPEEDUP_AT_MOST = 4.0

#: name -> (location, the seed's words): each table by its title, each figure of the text by its sentence
QUOTES: dict[str, tuple[str, str]] = {
    "T1": ("3.2, table 1", "表1. 使用データの属性"),
    "T2": ("3.3, table 2", "表2. アルゴリズム1 (付影処理なし)"),
    "T3": ("3.3, table 3", "表3. アルゴリズム2 (付影処理なし)"),
    "T4": ("3.3, table 4", "表4. アルゴリズム1 (影多角形法)"),
    "T5": ("3.3, table 5", "表5. アルゴリズム2 (影多角形法)"),
    "T6": ("3.3, table 6", "表6. アルゴリズム1 (レイキャスティング法)"),
    "T7": ("3.3, table 7", "表7. アルゴリズム2 (レイキャスティング法)"),
    "VP200_T5_C300_MS": ("3.3, table 5, VP200, first column (c300: see CORRECTED)",
                         "VP200 c250 c200 ... 合計 2059 1774 1433"),
    "VP200_T5_C300_FRAGMENTS_PER_S": ("3.3, table 5, VP200, first column", "処理面素数(実・影)/秒 843730 831707"),
    "SP8_EMPTY_LINE_FRACTION": ("3.2, note on table 1", "sp8は表示図形のスクリーンに占める割合が小さく、"
                                "全スクリーンラインの約30%ではデータがない"),
    "SLIST_SPEEDUP_AT_MOST": ("4.1 2)(ii)", "slistの更新処理はベクトル化されるが演算器を余り用いないため処理速度の向上は"
                              "高々4倍にとどまる"),
}
