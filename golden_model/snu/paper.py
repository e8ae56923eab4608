"""Every figure of seed 004 (the SNU graphics system) that our code and reports use, each with
the paper's words and where they stand in ``shared/seeds/004_*.txt``.

Nothing else under ``golden_model/`` or ``sim/`` defines a paper value for this machine.
:data:`QUOTES` maps each name to (location, the paper's words). Sums of table 1's clocks per
processor (99, 141, 69) and polygons/s worked out from them are not printed: the reports show
them as ``formula`` values.
"""

from __future__ import annotations

__all__ = ["PAPER_BUS_RATE", "PAPER_FRAME_S", "PAPER_INNER_LOOP_CLOCKS", "PAPER_INNER_LOOP_OPS", "PAPER_MFLOPS",
           "PAPER_POLYS_PER_S", "PAPER_TABLE1", "PAPER_TEXT_COUNTS", "PAPER_TOTAL_CLOCKS", "PAPER_TOTAL_OPS", "PAPER_TRAVERSAL_BPS",
           "PAPER_TRIANGLE_BYTES", "QUOTES"]

#: table 1, per triangle: operations, i860 clocks, percent of clocks
PAPER_TABLE1: dict[str, dict[str, float]] = {
    "vertex_transform": {"ops": 72, "clocks": 60, "percent": 19.4},
    "normal_transform": {"ops": 45, "clocks": 39, "percent": 12.6},
    "normalise": {"ops": 30, "clocks": 81, "percent": 26.2},
    "light": {"ops": 72, "clocks": 60, "percent": 19.4},
    "clip": {"ops": 24, "clocks": 24, "percent": 7.8},
    "perspective_divide": {"ops": 12, "clocks": 18, "percent": 5.8},
    "screen_map": {"ops": 15, "clocks": 27, "percent": 8.7},
}
PAPER_TOTAL_OPS = 270
PAPER_TOTAL_CLOCKS = 309
#: the text's Mflops for 100,000 polygons/s (4.2.1-4.2.5); clip is 1.8 in the text (18 compares)
PAPER_MFLOPS = {"vertex_transform": 7.2, "normal_transform": 4.5, "normalise": 3.0, "light": 7.2,
                "clip": 1.8, "perspective_divide": 1.2, "screen_map": 1.5}
#: Per-vertex operation mix the paper's text gives (x3 per triangle). ``div`` is a reciprocal.
#: The paper counts 1/sqrt as "2 real operations" (sqrt + reciprocal).
PAPER_TEXT_COUNTS: dict[str, dict[str, int]] = {
    # 4x4 matrix with w fixed at 1.0: 12 mul + 12 add
    "vertex_transform": {"mul": 12, "add": 12},
    # 3x3 matrix: 9 mul + 6 add
    "normal_transform": {"mul": 9, "add": 6},
    # sum of squares 3 mul + 2 add; 1 sqrt + 1 reciprocal; scale 3 mul
    "normalise": {"mul": 6, "add": 2, "sqrt": 1, "div": 1},
    # 12 mul, 10 add, 3 compares, 1 memory reference (exponent lookup)
    "light": {"mul": 12, "add": 10, "cmp": 3, "lookup": 1},
    # 6 compares per vertex against the view volume
    "clip": {"cmp": 6},
    # reciprocal of w, 3 multiplies
    "perspective_divide": {"div": 1, "mul": 3},
    # 3 mul (x1280, y1024, z 2^24) + 2 add (z flip, y flip)
    "screen_map": {"mul": 3, "add": 2},
}
#: 3.2: the pixel bus, as printed (400 ns / 5 = 80 ns would give 12.5)
PAPER_BUS_RATE = 12e6
#: abstract and conclusion: 100-pixel Gouraud polygons per second
PAPER_POLYS_PER_S = 100_000
#: the one second those 100,000 polygons take ("초 당")
PAPER_FRAME_S = 1.0
#: 4.3: integer operations per pixel of the Gouraud inner loop
PAPER_INNER_LOOP_OPS = 8
#: 4.3: i860 clocks per pixel in dual-instruction mode with the separate Z comparator
PAPER_INNER_LOOP_CLOCKS = 4
#: 4.1: bytes per triangle record (9 floats per vertex)
PAPER_TRIANGLE_BYTES = 108
#: 4.1: traversal bandwidth
PAPER_TRAVERSAL_BPS = 10e6

QUOTES: dict[str, tuple[str, str]] = {
    "PAPER_TABLE1": ("4.5, table 1", "꼭지점 변환 72 60 19.4 / 수직 벡터 변환 45 39 12.6 / 수직 벡터 정규화 30 81 26.2 / "
                     "광도 계산 72 60 19.4 / 절단 24 24 7.8 / 투상 12 18 5.8 / 화면 좌표 변환 15 27 8.7"),
    "PAPER_TOTAL_OPS": ("4.5, table 1", "총 계 270 회 309 클록 100 %"),
    "PAPER_TOTAL_CLOCKS": ("4.5, table 1", "총 계 270 회 309 클록 100 %"),
    "PAPER_MFLOPS": ("4.2.1-4.2.5", "7.2 Mflops ... 4.5 ... 3.0 Mflops ... 7.2 Mflops ... 1.8 Mflops ... 1.2 Mflops "
                     "... 1.5 Mflops"),
    "PAPER_TEXT_COUNTS": ("4.2.1-4.2.5", "12 회의 실수 곱셈, 10 회의 덧셈, 3 회의 실수 비교, 1 회의 메모리 참조 ... "
                          "w의 역수를 구하는 실수 연산 1 회, 각 좌표를 w의 역수로 곱하는 실수 곱셈 3 회 ... "
                          "3 회의 실수 곱셈과 2 회의 실수 덧셈"),
    "PAPER_BUS_RATE": ("3.2", "화소 버스의 통신속은 12 Mpixel/sec 이다"),
    "PAPER_POLYS_PER_S": ("abstract, 5", "100화소의 폴리곤을 초당 100,000개 그릴 수 있을 것으로 예상된다"),
    "PAPER_FRAME_S": ("abstract, 5", "초당 100,000개"),
    "PAPER_INNER_LOOP_OPS": ("4.3", "화소당 모두 8 회의 정수 동작"),
    "PAPER_INNER_LOOP_CLOCKS": ("4.3", "Z 버퍼 비교기가 따로 있는 경우에는 화소 당 4 클럭이 소요된다"),
    "PAPER_TRIANGLE_BYTES": ("4.1", "한 꼭지점마다 36 바이트가 필요하고 도형마다 108 바이트가 소요된다"),
    "PAPER_TRAVERSAL_BPS": ("4.1", "트래버스 과정에서 필요한 통신폭(bandwidth)은 초 당 10 Mbyte 정도이다"),
}
