"""The paper behind the SNU graphics system, as its seed text gives it
(``shared/seeds/004_259eba1ba2ec22c5.txt``): read by the demo page (``sim/report/demo.py``).
What the seed does not say is marked so."""

REFERENCE = {
    "title": "Simulation을 위한 고성능 그래픽 시스템의 개발에 관한 연구",
    "title_en": "A Study on the Development of High Performance Graphics System for Simulation",
    "authors": ["Gab Seon Rho", "Jaehyun Park", "Naehyuck Chang", "Jung Woo Park", "Kyunghoon Koo",
                "Jaeyoung Lee", "Wook Hyun Kwon"],
    "affiliation": "Department of Control and Instrumentation Engineering, Seoul National University",
    "venue": None,        # not in the seed text
    "year": None,         # not in the seed text
    "dated_by": "it calls PHIGS+ a standard settled in 1991 (\"1991년에 표준안으로 확정되었다\")",
    "seed": "004",
}
