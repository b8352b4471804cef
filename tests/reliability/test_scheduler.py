"""Issue 28: ``ipmc study --scheduler tcp://HOST:PORT`` where the port accepts but never answers,
or answers another protocol, ends with exit 2 naming the address within the stated timeout —
never a hang, never a length of exabytes read from "HTTP/1.1".  Fake servers run in a thread."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("distributed")          # the Dask backend is optional ('ipmc[dask]')

sys.path.insert(0, str(Path(__file__).parent))
from _faults import env  # noqa: E402


class FakeServer:
    """A TCP server on 127.0.0.1 that ``mode``: "silent" (accepts, never writes), "http" (answers a
    request with an HTTP error), "banner" (writes an HTTP status line on accept, as SSH/SMTP greet),
    "close" (accepts and closes), "huge" (writes an 8-byte length of 2^62)."""

    def __init__(self, mode: str):
        self.mode = mode
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._loop, daemon=True).start()

    def _loop(self):
        while True:
            try:
                c, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(c)
            try:
                if self.mode == "banner":
                    c.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 0\r\n\r\n")
                elif self.mode == "close":
                    c.close()
                elif self.mode == "huge":
                    c.sendall((1 << 62).to_bytes(8, "little"))
                elif self.mode == "http":
                    threading.Thread(target=self._http, args=(c,), daemon=True).start()
            except OSError:
                pass

    @staticmethod
    def _http(c):
        try:
            if c.recv(65536):
                c.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
        except OSError:
            pass

    def close(self):
        self.sock.close()
        for c in self.conns:
            c.close()


@pytest.mark.parametrize("mode", ["silent", "http", "banner", "close", "huge"])
def test_a_scheduler_that_does_not_speak_dask_is_exit_2_within_the_timeout(tmp_path, mode):
    srv = FakeServer(mode)
    addr = f"tcp://127.0.0.1:{srv.port}"
    try:
        t0 = time.monotonic()
        p = subprocess.run([sys.executable, "-m", "scenarios.cli", "study", "actuator_mc", "--out",
                            str(tmp_path / "t.csv"), "--quiet", "--scheduler", addr, "--scheduler-timeout", "2"],
                           env=env(), capture_output=True, text=True, timeout=120)
        took = time.monotonic() - t0
    finally:
        srv.close()
    assert p.returncode == 2, p.stderr[-1500:]
    assert addr in p.stderr and "Traceback" not in p.stderr and "MemoryError" not in p.stderr
    # the timeout (2 s) plus interpreter start-up and the study's validation, never the 75 s seen
    assert took < 2 + 15, f"{took:.1f} s"
    assert not (tmp_path / "t.csv").exists()


def test_a_port_nobody_listens_on_is_exit_2_naming_it(tmp_path, capsys):
    from scenarios.cli import main

    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()                                   # now closed: connection refused
    assert main(["study", "actuator_mc", "--out", str(tmp_path / "t.csv"), "--quiet", "--scheduler",
                 f"tcp://127.0.0.1:{port}", "--scheduler-timeout", "2"]) == 2
    assert f"tcp://127.0.0.1:{port}" in capsys.readouterr().err


def test_the_probe_accepts_a_real_scheduler():
    distributed = pytest.importorskip("distributed")
    from scenarios.study import probe_scheduler

    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster:
        probe_scheduler(cluster.scheduler_address, 10)
