"""The paper behind the matrix-pipeline generator, as its seed text gives it
(``shared/seeds/002_a1ff7020b0ad58f6.txt``, Russian; the text starts at the abstract): read by
the demo page (``sim/report/demo.py``). What the seed does not say is marked so."""

REFERENCE = {
    "title": None,        # not in the seed text (it starts at the abstract)
    "title_en": "Matrix-pipeline image generators on sparse rasters (our description from the abstract)",
    "authors": [],        # not in the seed text
    "affiliation": None,
    "venue": None,        # not in the seed text
    "year": None,         # not in the seed text
    "dated_by": "1995 or later: \"Работа поддержана Российским фондом фундаментальных исследований, № 95-01-00028\"",
    "seed": "002",
}
