"""Issue 47, high 2: a ``--scheduler`` address is answered at once. Every command that takes one
(sweep, soak, report, demo, synth --all) looks at what answers there before any work, under one
time limit: an HTTP server (the dashboard's port typed for the scheduler's), a server that sends
other bytes, or one that sends nothing is one line ``error: ...`` naming the address and what
answered, exit 2, no traceback (before, ``sweep`` and ``soak`` hung without a word, and a reply in
another protocol ended in "Unable to allocate 3.07 EiB")."""

from __future__ import annotations

import logging
import re
import socket
import subprocess
import sys
import threading
import time

import pytest
from rasterhw.golden_model.errors import RasterhwError
from rasterhw.sim.flow import tasks as T
from test_reliability import one_line_error

PY = sys.executable


@pytest.fixture(scope="module")
def http_server():
    """``python3 -m http.server`` on the loopback address (never another interface)."""
    p = subprocess.Popen([PY, "-u", "-m", "http.server", "0", "--bind", "127.0.0.1"], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, text=True)
    try:
        line = p.stdout.readline()
        port = int(re.search(r"port (\d+)", line).group(1))
        yield f"tcp://127.0.0.1:{port}"
    finally:
        p.terminate()
        p.wait(10)


def _serve(reply: bytes | None):
    """A raw TCP server on 127.0.0.1 that sends ``reply`` to every connection (``None``: nothing,
    the connection kept open); its address."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen()
    held = []

    def loop():
        while True:
            try:
                c, _ = srv.accept()
            except OSError:
                return
            if reply is None:
                held.append(c)
            else:
                c.sendall(reply)
                c.close()

    threading.Thread(target=loop, daemon=True).start()
    return srv, f"tcp://127.0.0.1:{srv.getsockname()[1]}"


def _cli(*args, timeout=60):
    t0 = time.monotonic()
    r = subprocess.run([PY, "-m", "rasterhw.sim.cli.main", *args], capture_output=True, text=True, timeout=timeout)
    return r, time.monotonic() - t0


COMMANDS = {
    "sweep": ("sweep", "render:zbm", "--param", "interleave=1,2", "--scene", "c50", "--size", "32x32"),
    "soak": ("soak", "--pixels", "10"),
    "report": ("report", "zbm", "--fast"),
    "demo": ("demo", "--out", "never-made"),
    "synth": ("synth", "--all", "--small"),
}


@pytest.mark.parametrize("cmd", list(COMMANDS))
def test_an_http_server_is_named_at_once_by_every_command(http_server, cmd, tmp_path):
    r, secs = _cli(*COMMANDS[cmd], "--scheduler", http_server)
    line = one_line_error(r, contains=http_server)
    assert "HTTP server" in line and "SimpleHTTP" in line
    assert secs < 30
    assert not (tmp_path / "never-made").exists()


def test_garbage_bytes_and_silence_are_one_line():
    srv, addr = _serve(b"\xff" * 64 + b"garbage")
    try:
        r, secs = _cli(*COMMANDS["sweep"], "--scheduler", addr)
        assert "does not speak Dask's protocol" in one_line_error(r, contains=addr) and secs < 30
    finally:
        srv.close()
    srv, addr = _serve(None)
    try:
        r, secs = _cli(*COMMANDS["soak"], "--scheduler", addr)
        assert "sent nothing" in one_line_error(r, contains=addr) and secs < 30
    finally:
        srv.close()


def test_a_real_scheduler_passes_and_its_dashboard_port_is_named():
    from distributed import LocalCluster

    with LocalCluster(n_workers=0, processes=False, dashboard_address="127.0.0.1:0", silence_logs=logging.ERROR,
                      scheduler_kwargs={"host": "127.0.0.1", "protocol": "tcp"}) as c:
        assert T.check_scheduler(c.scheduler_address) == ("address", c.scheduler_address)
        port = re.search(r":(\d+)/", c.dashboard_link).group(1)
        with pytest.raises(RasterhwError, match=r"tcp://127\.0\.0\.1:\d+ is not a Dask scheduler: an HTTP server.*"
                                                r"Dask dashboard\? The scheduler's own port is usually 8786"):
            T.check_scheduler(f"tcp://127.0.0.1:{port}")


def test_the_check_keeps_one_time_limit(monkeypatch):
    srv, addr = _serve(None)
    try:
        t0 = time.monotonic()
        with pytest.raises(RasterhwError, match="sent nothing"):
            T.check_scheduler(addr, limit_s=2.0)
        assert time.monotonic() - t0 < 3.0
    finally:
        srv.close()


def test_synth_scheduler_options_without_all_are_refused():
    for opt in (("--store", "s"), ("--fresh",), ("--scheduler", "serial")):
        r, _ = _cli("synth", "zbm-merger", *opt)
        one_line_error(r, contains="only with --all")
