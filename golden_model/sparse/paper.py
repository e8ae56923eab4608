"""Every figure of seed 002 (the matrix-pipeline generator on sparse rasters) that our code and
reports use, each with the paper's words and where they stand in ``shared/seeds/002_*.txt``.

Nothing else under ``golden_model/`` or ``sim/`` defines a paper value for this machine: the
reports, the theory and the cycle models import them from here. :data:`QUOTES` maps each name to
(location, the paper's words); the seed prints every number listed (tests/sparse/test_sparse_paper.py
finds each one in the seed's text).

The paper gives no buffer size: it asks for a "sufficient" input FIFO ("при малой размерности
матрицы и достаточном объеме FIFO") and refers the raster processor's micro-pipeline to its
reference [3] ("Такой микроконвейер подробно описан и исследован в [3]"). Every FIFO or inner
buffer depth in this project is therefore ours (``golden_model/sparse/vpcycles.py``).
"""

from __future__ import annotations

__all__ = ["PAPER_ALPHA", "PAPER_GROWTH_BASE", "PAPER_KP_KE", "PAPER_L", "PAPER_LOAD_MAX", "PAPER_M",
           "PAPER_PMAX_TAU", "PAPER_S_K", "PAPER_TESTS_PER_PRIMITIVE", "QUOTES"]

#: the crossing areas S_1..S_4 (text after formula (4))
PAPER_S_K = (0.0, 1.8, 23.3, 157.0)
#: the full raster 2^m x 2^m of figs. 3-6
PAPER_M = 10
#: the filter aperture alpha = beta (figs. 3-6)
PAPER_ALPHA = 2
#: the shape coefficient of figs. 3-6
PAPER_L = 1.514
#: k_p / k_e of figs. 5-6
PAPER_KP_KE = 1
#: P_max = 0.2 / tau: maximum performance in primitives per coverage-test time
PAPER_PMAX_TAU = 0.2
#: "in the average time of five coverage tests" per primitive at maximum performance (conclusion)
PAPER_TESTS_PER_PRIMITIVE = 5
#: the pipelines' load maximum near S = S_k, "practically up to 100 %" (fig. 6b text), as a fraction
PAPER_LOAD_MAX = 1.0
#: performance at large S grows "practically in proportion to the number of video processors 4^k"
PAPER_GROWTH_BASE = 4

#: the quotes are the seed's text as it stands, its OCR errors kept (Л = k, Si = S_1, 5з = S_3, 54 = S_4,
#: /и = m, а X /3 = 2̂ = alpha x beta = 2^2, Ртях = 0,2<7\ = P_max = 0.2/tau, 4*" = 4^k); our reading is
#: the comment above each constant
QUOTES: dict[str, tuple[str, str]] = {
    "PAPER_S_K": ("text after formula (4)", "Решив квадратное уравнение (4) для Л = 1, 2, 3, 4, а = 2 и L = 1,514, "
                  "получим Si = 0; S2 = 1,8; 5з = 23,3; 54 = 157."),
    "PAPER_M": ("text before fig. 3", "Разрешение полного растра фиксировано и составляет ... где /и = 10."),
    "PAPER_ALPHA": ("text before fig. 3", "Квадратная апертура фильтра а X /3 = 2\u0302"),
    "PAPER_L": ("text before fig. 3", "коэффициент формы многоугольника L= 1,514"),
    "PAPER_KP_KE": ("text of fig. 5", "m = 10, а = 2, L= 1,514 и кр/ке = 1"),
    "PAPER_PMAX_TAU": ("text of fig. 5", "Ртях = 0,2<7\\"),
    "PAPER_TESTS_PER_PRIMITIVE": ("conclusion", "При этом максимальная производительность соответствует в "
                                  "среднем времени пяти тестов покрытия"),
    "PAPER_LOAD_MAX": ("fig. 6b text", "характерно наличие максиму- ... MOB загрузки (практически до 100 %) в "
                       "окрестности S = Sk"),
    "PAPER_GROWTH_BASE": ("fig. 6a text", "производитель- ность растет практически пропорцио- нально количеству "
                          "видеопроцессоров 4*\"."),
}
