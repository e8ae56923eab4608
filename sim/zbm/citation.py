"""The paper behind ZB/M, as its seed text gives it (``shared/seeds/003_3355a922071bd992.txt``):
read by the demo page (``sim/report/demo.py``). What the seed does not say is marked so."""

REFERENCE = {
    "title": "マルチプロセッサ向き画像生成ユニット - Scanline Z-Buffer Merger -",
    "title_en": "Image Generation Unit for Multi Processor System - Scanline Z-Buffer Merger -",
    "authors": ["A. Nishimura", "T. Kobayashi", "Y. Wakayama", "K. Maenobu", "T. Nishizawa", "T. Sagishima"],
    "affiliation": "Media Research Laboratory, Matsushita Electric Industrial Co., Ltd.",
    "venue": None,        # not in the seed text (its layout, あらまし and 和文キーワード, is a Japanese technical report's)
    "year": None,         # not in the seed text
    "dated_by": "its latest citation is from 1992 (Reality Engine data sheet; Computer Graphics, 1992)",
    "seed": "003",
}
