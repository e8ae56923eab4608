"""The paper behind EXPERTS, as its seed text gives it (``shared/seeds/000_5ac5e14b809e6e93.txt``):
read by the demo page (``sim/report/demo.py``). What the seed does not say is marked so."""

REFERENCE = {
    "title": "並列処理方式による三次元色彩图形表示用プロセッサ",   # as the seed spells it (图: the scan's)
    "title_en": "A Parallel Processor Architecture for 3 Dimensional Graphics",   # the paper's own English title
    "authors": ["Haruo Niimi", "Yoshiro Imai", "Masayoshi Murakami", "Shinji Tomita", "Hiroshi Hagiwara"],
    "affiliation": "Kyoto University; Takuma Radio Technical College; Nippon Denshi Kagaku Co., Ltd.",
    "venue": None,        # not in the seed text
    "year": None,         # not in the seed text
    "dated_by": "its latest citation is from 1982 (IEEE CG&A, Mar. 1982)",
    "seed": "000",
}
