"""The paper behind the vector Z-buffer, as its seed text gives it
(``shared/seeds/001_96e5154526ae973d.txt``): read by the demo page (``sim/report/demo.py``).
What the seed does not say is marked so."""

REFERENCE = {
    "title": "ベクトル計算機を用いた3次元隠れ面消去処理",
    "title_en": "3-D hidden-surface removal on a vector computer (our translation; the seed gives no English title)",
    "authors": ["Katsuyoshi Kitai", "Haruo Niimi", "Shinji Tomita", "Hiroshi Hagiwara"],   # romanised by us
    "affiliation": "Kyoto University, Faculty of Engineering",
    "venue": None,        # not in the seed text
    "year": None,         # not in the seed text
    "dated_by": "its latest citation is from 1982; it names the FACOM VP100/VP200",
    "seed": "001",
}
