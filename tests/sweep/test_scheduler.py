"""Scheduler addresses (issue 40, class 7): a port that is not a dask scheduler is refused
within the connect timeout with one line, and no client is left to print its finaliser's
traceback; a server that speaks HTTP or garbage never makes dask allocate its "length"."""

from __future__ import annotations

import importlib.util
import os
import socket
import struct
import subprocess
import sys
import threading
import time

import pytest
from data.sweeps import TINY

from imdrive.errors import ConfigError

# the module is looked for, not imported: importing dask.distributed is 1-2 s of every
# worker's collection, and only these tests' worker needs it
if importlib.util.find_spec("distributed") is None:
    pytest.skip("could not import 'distributed'", allow_module_level=True)

from imdrive.sweep.scheduler import (  # noqa: E402
    _handshake,
    _our_handshake,
    check_scheduler_address,
    connect,
    probe_scheduler,
)


class _Server:
    """A local TCP server that answers every connection with ``reply(conn)``."""

    def __init__(self, reply):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.reply = reply
        self.address = f"tcp://127.0.0.1:{self.sock.getsockname()[1]}"
        self.done = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self):
        self.sock.settimeout(0.2)
        while not self.done.is_set():
            try:
                conn, _ = self.sock.accept()
            except OSError:
                continue
            threading.Thread(target=self._one, args=(conn,), daemon=True).start()

    def _one(self, conn):
        try:
            self.reply(conn)
            self.done.wait(30)
        except OSError:
            pass
        finally:
            conn.close()

    def close(self):
        self.done.set()
        self.sock.close()


def _http(conn):  # waits for a request, as an HTTP server (a dask dashboard) does
    conn.settimeout(30)
    conn.recv(65536)
    conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")


def _http_first(conn):  # a server that speaks first, in HTTP
    conn.sendall(b"HTTP/1.1 200 OK\r\n\r\n")


def _huge(conn):  # a frame length of 2**64 - 1: dask would allocate it
    conn.sendall(b"\xff" * 64)


def _exabytes(conn):  # 'HTTP/1.1' as a little-endian length is 3.5e18 bytes
    conn.sendall(b"HTTP/1.1")


def _small_garbage(conn):  # a plausible length, then bytes that are no dask frame
    body = b"\x05" * 40
    conn.sendall(struct.pack("<Q", len(body)) + body)


def _silent(conn):
    pass


def _closes(conn):
    conn.close()


SERVERS = {
    "http": _http,
    "http-first": _http_first,
    "huge-length": _huge,
    "exabyte-length": _exabytes,
    "small-garbage": _small_garbage,
    "silent": _silent,
    "closes": _closes,
}


@pytest.fixture
def server(request):
    s = _Server(SERVERS[request.param])
    s.name = request.param
    yield s
    s.close()


@pytest.mark.parametrize("server", SERVERS, indirect=True)
def test_a_port_that_is_not_a_scheduler_is_one_config_error_within_the_timeout(server):
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"--scheduler") as exc:
        connect(server.address, timeout_s=1.0)
    assert time.perf_counter() - t0 < 5.0
    assert "\n" not in str(exc.value)
    assert server.address in str(exc.value)


def test_inproc_address_without_a_scheduler_is_refused():
    with pytest.raises(ConfigError, match="no scheduler listens at inproc://x"):
        check_scheduler_address("inproc://x")


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf"), "10"])
def test_connect_timeout_must_be_a_positive_finite_number(value):
    with pytest.raises(ConfigError, match="--connect-timeout"):
        connect("tcp://127.0.0.1:1", timeout_s=value)


def test_our_handshake_is_read_as_one():
    """The probe's handshake parser accepts a dask handshake (ours, framed the way dask
    frames it) and nothing shorter or longer."""
    framed = _our_handshake()
    (n,) = struct.unpack("<Q", framed[:8])
    body = framed[8:]
    assert n == len(body)
    assert _handshake(body)["pickle-protocol"] >= 4
    assert _handshake(body[:-1]) is None
    assert _handshake(body + b"\0") is None
    assert _handshake(b"\0" * 16) is None


@pytest.mark.slow  # a scheduler in this process: about 2 s
@pytest.mark.parametrize("protocol", ["tcp", "ws"])
def test_a_real_scheduler_passes_the_probe_and_connects(protocol):
    # ws: the probe's WebSocket upgrade is granted by dask's own listener
    distributed = pytest.importorskip("dask.distributed")
    with distributed.LocalCluster(
        n_workers=0, processes=False, protocol=protocol, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        assert cluster.scheduler_address.startswith(f"{protocol}://")
        probe_scheduler(cluster.scheduler_address, 5.0)
        client = connect(cluster.scheduler_address, 5.0)
        try:
            assert client.status == "running"
        finally:
            client.close()


@pytest.mark.slow  # a process of its own (the client's finaliser runs at exit): about 5 s
@pytest.mark.parametrize("server", ["http", "exabyte-length"], indirect=True)
def test_sweep_on_a_server_that_is_not_a_scheduler_exits_2_with_one_line(tmp_path, server):
    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "imdrive",
            "sweep",
            str(f),
            "--out",
            str(tmp_path / "s"),
            "--scheduler",
            server.address,
            "--connect-timeout",
            "2",
            "-q",
        ],  # fmt: skip
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "Exception ignored" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("imdrive: error: --scheduler: "), lines
    assert "out of memory" not in proc.stderr
    assert not (tmp_path / "s").exists()


@pytest.mark.parametrize("scheme", ["tls", "wss"])
def test_a_tls_address_without_dask_s_tls_configuration_is_refused_naming_it(scheme, monkeypatch):
    # before: dask's own "TLS expects a `ssl_context` argument", after connecting
    for key in [k for k in os.environ if k.startswith("DASK_DISTRIBUTED__COMM__TLS")]:
        monkeypatch.delenv(key)
    with pytest.raises(ConfigError, match=r"--scheduler: .* needs dask's TLS configuration") as e:
        check_scheduler_address(f"{scheme}://127.0.0.1:1")
    assert "distributed.comm.tls.ca-file" in str(e.value)


WS_EXPECTED = {
    "http": "answers HTTP 400",
    "http-first": "answers HTTP 200",
    "small-garbage": "greets as a TCP dask scheduler: use tcp://",
    "silent": "did not answer a WebSocket upgrade within 1 s",
    "huge-length": "its answer is no HTTP",
}


@pytest.mark.parametrize("server", list(WS_EXPECTED), indirect=True)
def test_a_ws_address_whose_server_grants_no_websocket_upgrade_is_refused(server):
    # before: dask's "Timed out trying to connect" whatever answered
    address = server.address.replace("tcp://", "ws://")
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=r"--scheduler") as exc:
        connect(address, timeout_s=1.0)
    assert time.perf_counter() - t0 < 5.0
    assert WS_EXPECTED[server.name] in str(exc.value)
