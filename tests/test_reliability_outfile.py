"""Issue 33, high 2 and the medium "files are 0600": the one writer of output files
(sim/outfile.py) writes through links, into devices and FIFOs, in place for hard-linked files,
atomically (keeping the mode) for the rest, new files by the umask; refuses folders and inputs."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
import threading

import numpy as np
import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.outfile import (
    atomic_path,
    check_image_output,
    check_output,
    write_image,
    write_text,
)

PY = sys.executable


def _cli(*args, cwd=None, **kw):
    return subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, cwd=cwd, timeout=300, **kw)


def test_new_file_honours_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        write_text(tmp_path / "a.v", "x")
        os.umask(0o077)
        write_text(tmp_path / "b.v", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.v").stat().st_mode) == 0o644
    assert stat.S_IMODE((tmp_path / "b.v").stat().st_mode) == 0o600


def test_replaced_file_keeps_its_mode(tmp_path):
    f = tmp_path / "a.v"
    f.write_text("old")
    os.chmod(f, 0o640)
    write_text(f, "new")
    assert f.read_text() == "new" and stat.S_IMODE(f.stat().st_mode) == 0o640


def test_symlink_is_written_through(tmp_path):
    (tmp_path / "real.v").write_text("old")
    (tmp_path / "link.v").symlink_to("real.v")
    write_text(tmp_path / "link.v", "new")
    assert (tmp_path / "link.v").is_symlink()
    assert (tmp_path / "real.v").read_text() == "new"


def test_hard_linked_file_is_rewritten_in_place(tmp_path):
    a, b = tmp_path / "a.v", tmp_path / "b.v"
    a.write_text("old")
    os.link(a, b)
    ino = a.stat().st_ino
    write_text(a, "new")
    assert a.stat().st_ino == ino and b.read_text() == "new"


def test_fifo_is_written_into_not_replaced(tmp_path):
    p = tmp_path / "p.v"
    os.mkfifo(p)
    got = []
    t = threading.Thread(target=lambda: got.append(open(p).read()))
    t.start()
    write_text(p, "module m; endmodule\n")
    t.join(timeout=30)
    assert got == ["module m; endmodule\n"]
    assert stat.S_ISFIFO(os.stat(p).st_mode)


def test_a_device_stays_a_device(tmp_path):
    """Like ``-o /dev/null`` as root (the probe's case), on a null device of the test's own, so a
    regression cannot replace the system's /dev/null."""
    dev = tmp_path / "null"
    try:
        os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device node needs root")
    write_text(dev, "x")
    assert stat.S_ISCHR(os.stat(dev).st_mode)


def test_folder_names_are_refused(tmp_path):
    for name in (str(tmp_path / "newdir") + "/", str(tmp_path)):
        with pytest.raises(RasterhwError, match="is a folder"):
            check_output(name)
        with pytest.raises(RasterhwError, match="is a folder"):
            write_text(name, "x")
    assert not (tmp_path / "newdir").exists()


def test_output_that_is_an_input_is_refused(tmp_path):
    a = tmp_path / "a.png"
    a.write_bytes(b"x")
    (tmp_path / "alias.png").symlink_to(a)
    for name in (a, tmp_path / "alias.png", tmp_path / "." / "a.png"):
        with pytest.raises(RasterhwError, match="also an input"):
            check_image_output(name, inputs=[a])


def test_interrupted_write_leaves_the_target_and_no_temporary(tmp_path):
    f = tmp_path / "a.v"
    f.write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_path(f) as tmp:
            tmp.write_text("half")
            raise KeyboardInterrupt
    assert f.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["a.v"]


def test_cli_verilog_to_stdout_fifo_link_and_folder(tmp_path):
    r = _cli("verilog", "zbm-merger", "-o", "-")
    assert r.returncode == 0 and b"module" in r.stdout
    r = _cli("verilog", "zbm-merger", "-o", "newdir/", cwd=tmp_path)
    assert r.returncode == 2 and r.stderr.decode().strip() == "error: -o 'newdir/' is a folder, not a file name"
    assert not (tmp_path / "newdir").exists()


def test_cli_compare_refuses_to_overwrite_an_input(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    write_image(a, np.zeros((4, 4, 3), np.uint8))
    write_image(b, np.full((4, 4, 3), 9, np.uint8))
    before = a.read_bytes()
    r = _cli("compare", str(a), str(b), "-o", str(a))
    assert r.returncode == 2 and b"also an input" in r.stderr and b"Traceback" not in r.stderr
    assert a.read_bytes() == before


def test_cli_image_to_stdout(tmp_path):
    a = tmp_path / "a.png"
    write_image(a, np.zeros((4, 4, 3), np.uint8))
    r = _cli("compare", str(a), str(a), "-o", "-")
    assert r.returncode == 0 and r.stdout.startswith(b"\x89PNG")


def test_common_image_formats_without_loading_every_pillow_plugin():
    """``image_format`` answers .png (and the other formats Pillow's preinit registers) without
    loading every plugin, with the format the full table (``image_formats``) gives; an extension
    only a later plugin knows is still found, an unknown one is None."""
    code = ("import sys\n"
            "from PIL import Image\n"
            "from rasterhw.sim.outfile import image_format, image_formats\n"
            "assert image_format('.png') == 'PNG'\n"
            "assert 'PIL.TiffImagePlugin' not in sys.modules\n"
            "pre = {e: f for e, f in Image.EXTENSION.items() if f in Image.SAVE}\n"
            "assert len(pre) >= 5\n"
            "full = image_formats()\n"
            "assert all(full[e] == f for e, f in pre.items()), pre\n"
            "assert image_format('.tif') == full['.tif'] == 'TIFF' and image_format('.nope') is None\n"
            "print('ok')\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and r.stdout.strip() == "ok", r.stderr
