# amaranth: UnusedElaboratable=no
"""Issue 14, row by row: every input a user can give gets the right result or one line
``error: ...`` with exit status 2, no traceback and no partial output file. Each test is named
after what it protects (rows 1 and 2 are covered by tests/zbm/test_zbm_driver.py::
test_float_tolerance_when_last_triangles_cover_no_pixel and tests/test_cli.py::
test_typed_block_parameters; the row-2 false case is here too)."""

from __future__ import annotations

import inspect
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError

PY = sys.executable
TRI = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def run(*args: str, cwd=None, env=None, timeout=300) -> subprocess.CompletedProcess:
    e = dict(os.environ, **(env or {}))
    return subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True, cwd=cwd,
                          env=e, timeout=timeout)


def one_line_error(r: subprocess.CompletedProcess, *, contains: str = "") -> str:
    assert r.returncode == 2, (r.returncode, r.stdout, r.stderr)
    assert "Traceback" not in r.stderr
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    assert contains in lines[0], lines[0]
    return lines[0]


# ------------------------------------------------------------------ row 2
def test_p_false_is_false_not_a_truthy_string():
    from rasterhw.hdl.zbm.unit import ZbmUnit
    from rasterhw.sim.engines.verilog import parse_params

    assert parse_params(("head=false",), ZbmUnit) == {"head": False}
    assert parse_params(("head=1", "interleave=2"), ZbmUnit) == {"head": True, "interleave": 2}
    # issue 47: digits as --size reads them (0x2 was read as 2; now refused like --size 0x40)
    for bad in ("0x2", "1_0", "\u0662", "\uff12"):
        with pytest.raises(RasterhwError, match="integer in ASCII digits"):
            parse_params((f"interleave={bad}",), ZbmUnit)


# ------------------------------------------------------------------ row 3
@pytest.mark.parametrize("encode", [
    lambda t: ("# caf\u00e9\n" + t).encode("latin-1"),
    lambda t: b"\xef\xbb\xbf" + t.encode(),
    lambda t: ("# caf\u00e9\n" + t).encode("utf-16"),
    lambda t: t.encode("utf-16-le"),
    lambda t: t.encode("utf-16-be"),
    lambda t: ("# caf\u00e9\n" + t).encode("utf-8"),
], ids=["latin-1", "utf-8-bom", "utf-16-bom", "utf-16-le", "utf-16-be", "utf-8"])
def test_obj_in_any_common_encoding_loads_like_plain_utf8(tmp_path, encode):
    from rasterhw.golden_model.meshio import load_mesh

    ref = tmp_path / "ref.obj"
    ref.write_text(TRI)
    other = tmp_path / "other.obj"
    other.write_bytes(encode(TRI))
    a, b = load_mesh(ref), load_mesh(other)
    assert np.array_equal(a.positions, b.positions) and a.positions.shape == (1, 3, 3)


def test_ply_with_a_latin1_comment_loads(tmp_path):
    from rasterhw.golden_model.meshio import load_mesh

    head = ("ply\nformat ascii 1.0\ncomment caf\u00e9\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n")
    p = tmp_path / "l1.ply"
    p.write_bytes(head.encode("latin-1") + b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert load_mesh(p).positions.shape == (1, 3, 3)


def test_decode_text_guesses():
    from rasterhw.golden_model.meshio import decode_text

    assert decode_text(b"\xef\xbb\xbfv 1") == ("v 1", "utf-8")
    assert decode_text("v 1".encode("utf-16"))[0] == "v 1"
    assert decode_text(b"# \xe9") == ("# \u00e9", "latin-1")
    assert decode_text("v \u00e9".encode("utf-32")) == ("v \u00e9", "utf-32-le")


# ------------------------------------------------------------------ row 4
def test_obj_face_index_zero_is_refused_not_read_as_last_vertex(tmp_path):
    p = tmp_path / "zero.obj"
    p.write_text(TRI.replace("f 1 2 3", "f 1 2 0"))
    one_line_error(run("render", str(p), "-o", str(tmp_path / "z.png")), contains="index 0")
    assert not (tmp_path / "z.png").exists()


def test_obj_negative_indices_still_work(tmp_path):
    from rasterhw.golden_model.meshio import load_mesh

    p = tmp_path / "neg.obj"
    p.write_text(TRI.replace("f 1 2 3", "f -3 -2 -1"))
    assert load_mesh(p).positions.shape == (1, 3, 3)


# ------------------------------------------------------------------ row 5
@pytest.mark.parametrize("args", [
    ("render", "c300", "-o", "out.txt"),
    ("render", "c300", "-o", "noext"),
    ("sim", "pixelbus", "--engine", "pysim", "-o", "x.txt"),
])
def test_unknown_output_extension_is_refused_before_any_work(tmp_path, args):
    t0 = time.perf_counter()
    one_line_error(run(*args, cwd=tmp_path), contains="image extension")
    assert time.perf_counter() - t0 < 20  # refused up front, not after a render
    assert not any(tmp_path.iterdir())


def test_compare_output_extension_checked_first(tmp_path):
    from PIL import Image

    for n in ("a.png", "b.png"):
        Image.new("RGB", (4, 4)).save(tmp_path / n)
    one_line_error(run("compare", "a.png", "b.png", "-o", "d.txt", cwd=tmp_path), contains="image extension")
    assert not (tmp_path / "d.txt").exists()


def test_failed_image_write_leaves_no_partial_file(tmp_path):
    from rasterhw.sim.outfile import write_image

    with pytest.raises(RasterhwError):
        write_image(tmp_path / "x.png", np.zeros((4, 4, 7), np.uint8))  # not an image Pillow can save
    assert not any(tmp_path.iterdir())


# ------------------------------------------------------------------ row 6
def test_frame_too_big_for_memory_is_one_line_before_allocating(tmp_path):
    t0 = time.perf_counter()
    line = one_line_error(run("render", "c300", "--size", "16384x16384", "-o", "big.png", cwd=tmp_path,
                              env={"RASTERHW_MEMORY_LIMIT": "512M"}), contains="16384x16384")
    assert "needs about" in line and "available" in line
    assert time.perf_counter() - t0 < 30 and not any(tmp_path.iterdir())


def test_golden_arch_frame_too_big_is_one_line(tmp_path):
    one_line_error(run("render", "c50", "--arch", "snu", "--size", "16384x16384", cwd=tmp_path,
                       env={"RASTERHW_MEMORY_LIMIT": "1G"}), contains="needs about")


def test_tiled_reference_is_exactly_the_full_frame(monkeypatch):
    from rasterhw.golden_model import reference as R

    for seed, (w, h) in enumerate([(97, 61), (16, 200), (300, 7)]):
        tris = R.random_triangles(w, h, 250, mean_area=300, seed=seed)
        f = R.rasterise(tris)
        for tile in (1, w, 5 * w + 3, w * h):
            monkeypatch.setattr(R, "TILE_PIXELS", tile)
            rgb, counts = R.rasterise_rgb8(tris)
            assert np.array_equal(rgb, f.to_rgb8()), (seed, tile)
            assert counts == {"fragments": f.fragments, "pixels_written": f.pixels_written,
                              "pixels_covered": f.pixels_covered}


def test_tiled_reference_memory_is_a_few_bytes_per_pixel(monkeypatch):
    import tracemalloc

    from rasterhw.golden_model import reference as R

    monkeypatch.setattr(R, "TILE_PIXELS", 1 << 18)
    tris = R.random_triangles(2048, 2048, 2000, mean_area=400, seed=3)
    tracemalloc.start()
    try:
        R.rasterise_rgb8(tris)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak / (2048 * 2048) < 20, peak  # the full Frame path needs ~115 bytes per pixel
    assert peak < R.rasterise_rgb8_memory(2048, 2048, 2000)


def test_memory_limit_parsing():
    from rasterhw.golden_model.memcheck import parse_bytes

    assert parse_bytes("512M") == 512 << 20 and parse_bytes("2G") == 2 << 30 and parse_bytes("100") == 100
    with pytest.raises(RasterhwError):
        parse_bytes("lots")


# ------------------------------------------------------------------ row 7
def test_compare_reads_images_above_pillows_bomb_limit(tmp_path, monkeypatch):
    from PIL import Image
    from rasterhw.sim.imageio import read_rgb8_pair

    a = np.random.default_rng(0).integers(0, 256, (64, 80, 3), dtype=np.uint8)
    Image.fromarray(a).save(tmp_path / "a.png")
    Image.fromarray(a).save(tmp_path / "b.png")
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)  # 5120 px is a "bomb" to Pillow now
    ia, ib = read_rgb8_pair(tmp_path / "a.png", tmp_path / "b.png")
    assert np.array_equal(ia, a) and np.array_equal(ib, a)
    assert Image.MAX_IMAGE_PIXELS == 1000  # restored


def test_compare_too_big_for_memory_is_one_line(tmp_path):
    from PIL import Image

    for n in ("a.png", "b.png"):
        Image.new("RGB", (300, 300)).save(tmp_path / n)
    one_line_error(run("compare", "a.png", "b.png", cwd=tmp_path, env={"RASTERHW_MEMORY_LIMIT": "100K"}),
                   contains="compare 300x300 needs about")


def test_compare_in_bands_gives_whole_image_counts(monkeypatch):
    from rasterhw.golden_model import compare as C

    rng = np.random.default_rng(1)
    a = rng.integers(0, 256, (37, 23, 3))
    b = np.where(rng.random((37, 23, 1)) < 0.2, rng.integers(0, 256, (37, 23, 3)), a)
    whole = C.compare_images(a, b, tolerance=3), C.diff_image(a, b, tolerance=3)
    monkeypatch.setattr(C, "BAND_PIXELS", 23 * 2)
    assert C.compare_images(a, b, tolerance=3) == whole[0]
    assert np.array_equal(C.diff_image(a, b, tolerance=3), whole[1])


# ------------------------------------------------------------------ row 8
def test_verilog_pixelbus_default_is_quick_and_uses_the_verilog_ram(tmp_path):
    t0 = time.perf_counter()
    r = run("verilog", "pixelbus", "-o", "pixelbus.v", cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert time.perf_counter() - t0 < 60 and r.stdout == ""
    text = (tmp_path / "pixelbus.v").read_text()
    assert len(text) < 2_000_000 and "module rasterhw_pixelbus_ram" in text


def test_pixelbus_ram_auto_keeps_memory_for_small_frames():
    from rasterhw.hdl.snu.pixelbus import PixelBus

    assert PixelBus(width=40, height=16).ram == "memory"
    assert PixelBus().ram == "verilog"
    assert PixelBus(width=40, height=16, ram="verilog").ram == "verilog"


# ------------------------------------------------------------------ row 9
def test_failed_elaboration_prints_one_line_without_amaranth_warnings(tmp_path):
    one_line_error(run("verilog", "zbm-unit", "-p", "capacity=0", "-o", "t.v", cwd=tmp_path), contains="capacity")
    assert not (tmp_path / "t.v").exists()


# ------------------------------------------------------------------ row 10
def test_run_folders_are_removed_when_a_run_fails(tmp_path):
    from rasterhw.sim import workdirs

    with pytest.raises(RuntimeError):
        with workdirs.run_folder(tmp_path) as d:
            (d / "dump").write_text("x")
            raise RuntimeError("simulated failure")
    d = workdirs.temp_run_folder(tmp_path)
    workdirs.cleanup()
    assert not d.exists() and not any(tmp_path.iterdir())


def test_simulator_child_dies_with_an_interrupted_parent(tmp_path):
    """SIGTERM to a CLI process mid-run: its run folder is removed and its child is gone."""
    script = textwrap.dedent(f"""
        import signal, sys
        from rasterhw.sim import workdirs
        from rasterhw.sim.cli import main as cli
        signal.signal(signal.SIGTERM, cli._terminate)
        d = workdirs.temp_run_folder({str(tmp_path)!r})
        print(d, flush=True)
        try:
            workdirs.run_child(["sleep", "120"])
        finally:
            workdirs.cleanup()
    """)
    p = subprocess.Popen([PY, "-c", script], stdout=subprocess.PIPE, text=True)
    run_dir = p.stdout.readline().strip()
    assert os.path.isdir(run_dir)
    child = None
    for _ in range(100):
        kids = subprocess.run(["pgrep", "-P", str(p.pid)], capture_output=True, text=True).stdout.split()
        if kids:
            child = int(kids[0])
            break
        time.sleep(0.05)
    assert child is not None
    p.send_signal(signal.SIGTERM)
    p.wait(timeout=30)
    time.sleep(0.2)
    assert not os.path.exists(run_dir)
    assert not os.path.exists(f"/proc/{child}") or "Z" in open(f"/proc/{child}/stat").read().split()[2]


def test_child_killed_on_timeout():
    from rasterhw.sim.workdirs import run_child

    t0 = time.perf_counter()
    with pytest.raises(subprocess.TimeoutExpired):
        run_child(["sleep", "60"], timeout=0.3)
    assert time.perf_counter() - t0 < 10


# ------------------------------------------------------------------ row 11
def test_concurrent_builds_of_one_folder_take_turns(tmp_path):
    script = textwrap.dedent(f"""
        import sys, time
        from rasterhw.sim.workdirs import build_lock
        with build_lock({str(tmp_path / 'b')!r}):
            t = time.time()
            time.sleep(0.8)
            print(t, time.time())
    """)
    ps = [subprocess.Popen([PY, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
          for _ in range(2)]
    outs = [p.communicate(timeout=60) for p in ps]
    (a0, a1), (b0, b1) = (tuple(map(float, o[0].split())) for o in outs)
    assert a1 <= b0 + 0.05 or b1 <= a0 + 0.05  # never inside the lock together
    assert any("waiting for another build" in o[1] for o in outs)


def test_failed_verilator_build_is_one_line_naming_the_log(tmp_path):
    from rasterhw.sim.engines.runner import build_plain_verilator

    bad = tmp_path / "bad.v"
    bad.write_text("module tb_bad(; endmodule\n")
    with pytest.raises(RasterhwError) as e:
        build_plain_verilator(f"bad-{os.getpid()}", "tb_bad", [bad], params={})
    msg = str(e.value)
    assert "\n" not in msg and "build failed" in msg and "build.log" in msg


# ------------------------------------------------------------------ row 12
def test_every_listed_block_has_defaults_for_every_parameter():
    from rasterhw.sim import registry

    for name, ref in registry.blocks().items():
        for p in inspect.signature(registry.load(ref)).parameters.values():
            assert p.default is not inspect.Parameter.empty, f"{name}: {p.name} has no default"


def test_pixelbus_bank_generates_with_defaults(tmp_path):
    r = run("verilog", "pixelbus-bank", "-o", "bank.v", cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "module pixelbus_bank" in (tmp_path / "bank.v").read_text()


# ------------------------------------------------------------------ row 13
def test_pixelbus_progress_goes_to_stderr(capsys):
    from rasterhw.golden_model.snu.pixelstream import PixelStream
    from rasterhw.sim.snu.scene import simulate_pixelbus

    rng = np.random.default_rng(0)
    s = PixelStream(8, 4, rng.integers(0, 32, 20), rng.integers(0, 1 << 24, 20), rng.integers(0, 1 << 24, 20),
                    rng.integers(0, 2, 20))
    assert simulate_pixelbus(s, engine="pysim", progress=True)["mismatches"] == 0
    out = capsys.readouterr()
    assert out.out == "" and "pixelbus:" in out.err


def test_size_is_checked_before_the_mesh_loads(tmp_path):
    # the mesh does not exist: the size error must come first
    one_line_error(run("render", str(tmp_path / "missing.obj"), "--size", "5_0x5_0"), contains="--size")


@pytest.mark.parametrize("text", ["5_0x5_0", "+5x5", "-5x5", "5x5x5", "0x10", "16385x1", " x ", "5.0x5"])
def test_size_parser_takes_plain_digits_only(text):
    from rasterhw.sim.cli.main import parse_size

    with pytest.raises(RasterhwError):
        parse_size(text)
    assert parse_size(" 64 x 32 ") == (64, 32) and parse_size("8*8") == (8, 8)


def test_conflicting_interleave_is_reported(tmp_path):
    one_line_error(run("verilog", "zbm-unit", "-p", "interleave=1", "--interleave", "2", "-o", "t.v", cwd=tmp_path),
                   contains="contradicts")


def test_back_facing_only_scene_warns_that_nothing_was_drawn(tmp_path):
    p = tmp_path / "back.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\n")  # clockwise as seen by the framing camera
    r = run("render", str(p), "--size", "32x32", "-o", str(tmp_path / "b.png"), "--json")
    assert r.returncode == 0, r.stderr
    if json.loads(r.stdout)["pixels_written"] == 0:
        assert "warning: nothing drawn" in r.stderr and "back-facing" in r.stderr
    front = tmp_path / "front.obj"
    front.write_text(TRI)
    r = run("render", str(front), "--size", "32x32", "-o", str(tmp_path / "f.png"))
    assert r.returncode == 0 and "warning" not in r.stderr


def test_render_reports_progress_per_tile():
    from rasterhw.golden_model import reference as R

    rows = []
    tris = R.random_triangles(64, 50, 10, seed=1)
    rgb, _ = R.rasterise_rgb8(tris, progress=rows.append)
    assert sum(rows) == 50 and len(rows) >= 25 and np.array_equal(rgb, R.rasterise(tris).to_rgb8())


def test_pixelbus_frame_run_folder_is_removed_when_the_run_is_interrupted(monkeypatch, tmp_path):
    """Issue 33: the SNU frame's run folder (115 MB at snu-100k) is a shared run folder: Ctrl-C
    (and SIGTERM: ``workdirs.cleanup``, which removes every folder still registered) removes it,
    where ``tempfile.mkdtemp`` left it. The frame runs on the generic Verilator engine
    (``frame.run_frame_engine``, ``FrameBench``; the dedicated bench it ran on is retired): its
    build is stubbed, its run interrupted once the stimulus is written."""
    import numpy as np
    from rasterhw.golden_model.pipeline import run_geometry
    from rasterhw.golden_model.scenes import build_scene
    from rasterhw.golden_model.snu.gouraud import scan_convert
    from rasterhw.sim import workdirs
    from rasterhw.sim.engines import verilator
    from rasterhw.sim.snu import scene as frame

    exe = tmp_path / "model" / "obj_dir" / "Vtb"
    exe.parent.mkdir(parents=True)
    seen = []
    monkeypatch.setattr(verilator, "build_plain_verilator", lambda *a, **k: (exe, 0.0))

    def interrupted(_exe, _args, *, run_dir, maxcyc, profile=None):
        seen.append((run_dir, run_dir.is_dir(), run_dir in workdirs._live, sorted(f.name for f in run_dir.iterdir())))
        raise KeyboardInterrupt

    monkeypatch.setattr(verilator, "run_plain_verilator", interrupted)
    s = scan_convert(run_geometry(build_scene("c50"), 16, 8, z_bits=24, z_far_is_zero=True))
    p = frame.producer_gaps(run_geometry(build_scene("c50"), 16, 8, z_bits=24, z_far_is_zero=True), s)
    sched = frame.golden_schedule(s, p["gaps"], p["first_work"], ratio=p["ratio"])
    with pytest.raises(KeyboardInterrupt):
        frame.run_frame_engine(s, np.zeros(len(s), np.int64), sched)
    (run_dir, was_dir, registered, files), = seen
    # while it ran: a real folder under the build, registered for cleanup, holding the stimulus
    assert was_dir and registered and {"i_pipe0.bin", "i_pipe1.bin"} <= set(files)
    assert run_dir.parent == exe.parent.parent
    # the interrupt removed it on its way out; nothing is left for cleanup either
    assert not run_dir.exists() and run_dir not in workdirs._live
    workdirs.cleanup()                       # what the CLI's signal handling runs
    assert not run_dir.exists()


def test_decode_text_detects_what_latin1_would_garble():
    """Without a mark, the detector (charset-normalizer) reads a Cyrillic or Japanese comment and
    BOM-less UTF-16; what it cannot place is Latin-1; the geometry loads the same either way."""
    from rasterhw.golden_model.meshio import decode_text

    obj = "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    for text, enc in (("# Модель экспортирована из Blender" + obj, "cp1251"),
                      ("# ポリゴンモデル、ブレンダーから" + obj, "shift_jis")):
        got, _how = decode_text(text.encode(enc))
        assert got == text
    assert decode_text(("v 1 2 3" + obj).encode("utf-16-be")) == ("v 1 2 3" + obj, "utf-16-be")
    assert decode_text(("# caf\u00e9" + obj).encode("utf-8")) == ("# caf\u00e9" + obj, "utf-8")
    # whatever it decides for a Western comment, the lines and numbers come through
    got, _how = decode_text(("# caf\u00e9 mod\u00e8le" + obj).encode("latin-1"))
    assert got.splitlines()[1:] == obj.splitlines()[1:]
