"""Connecting to a dask.distributed scheduler (``imdrive sweep --scheduler ADDRESS``).

A ``dask.distributed.Client`` trusts whatever answers on the address. Pointed at a port that
is not a dask scheduler it misbehaves: an HTTP server's reply ``HTTP/1.1`` is read as the
length of a message (3.5e18 bytes: "out of memory"), a server that accepts and stays silent
hangs the handshake with no timeout at all, and a client whose start failed prints its
finaliser's traceback 20 s later. So the address is settled before a client is made:

1. its form and protocol (:func:`check_scheduler_address`);
2. for TCP, the scheduler's greeting (:func:`probe_scheduler`): a dask server sends its
   handshake, a small msgpack table with ``python`` and ``pickle-protocol``, as soon as it
   accepts a connection. The probe reads at most :data:`GREETING_MAX_BYTES` of it within the
   connect timeout and answers with a handshake of its own, so the scheduler sees an ordinary
   client come and go. Anything else (silence, an HTTP reply, bytes that are not a dask
   frame) is refused before the client exists;
3. for ``inproc://``, a scheduler listening in this process;
4. the client itself, made with the same timeout; any failure is one line on
   ``--scheduler`` and the half-made client is closed quietly.

For ``tls://`` and ``wss://`` the client needs dask's TLS configuration (the certificate
authority, this client's certificate and key): without it every such address is refused at
once, naming the settings, instead of dask's "TLS expects a `ssl_context` argument" after the
connection. Their own handshake is left to the client (it holds the security configuration).
For ``ws://``, the probe asks for the WebSocket upgrade a dask client asks for and refuses a
server that does not grant it (a TCP scheduler, a dashboard, a silent port) within the
timeout, with what it saw, instead of dask's "Timed out trying to connect".

Functions
---------
check_scheduler_address
    The address's form and protocol; for TCP and TLS, a port that answers.
probe_scheduler
    Whether a dask scheduler greets on a TCP address, or grants a WebSocket upgrade on a
    ``ws://`` one.
connect
    A connected ``dask.distributed.Client``, or :class:`~imdrive.errors.ConfigError`.
"""

from __future__ import annotations

import functools
import socket
import struct
import time

from imdrive.errors import ConfigError, check_number

#: Seconds a scheduler has to accept the connection and greet (``--connect-timeout``).
CONNECT_TIMEOUT_S = 10.0
#: Seconds of the first TCP check of a port (before any dask code runs).
PROBE_TIMEOUT_S = 5.0
#: The largest greeting read: a dask handshake is under 100 bytes.
GREETING_MAX_BYTES = 4096


def check_scheduler_address(address, timeout_s: float = PROBE_TIMEOUT_S) -> tuple[str, str]:
    """``(scheme, location)`` of a dask scheduler address, refused at once when it cannot be
    one, and for TCP and TLS when nothing answers on its port.

    Parameters
    ----------
    address : str
        ``tcp://host:port``, ``host:port``, ``tls://...``, ``inproc://...``, ...
    timeout_s : float
        Seconds the port has to accept a TCP connection.

    Raises
    ------
    ConfigError
        On ``--scheduler``, naming the problem.
    """
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.comm.registry import backends

    if not isinstance(address, str) or not address.strip():
        raise ConfigError("--scheduler", "must be a scheduler address such as tcp://host:8786")
    bad = next((c for c in address if c.isspace() or not c.isprintable()), None)
    if bad is not None:
        raise ConfigError("--scheduler", f"{address[:60]!r} is not an address (it holds {bad!r})")
    if len(address) > 1000:
        raise ConfigError("--scheduler", f"{address[:60]!r}... is not an address (too long)")
    try:
        scheme, loc = parse_address(address, strict=False)
    except ValueError as exc:
        raise ConfigError("--scheduler", f"{address!r} is not an address: {exc}") from None
    if scheme not in backends:
        raise ConfigError(
            "--scheduler", f"unknown protocol {scheme!r} in {address!r} (known: {sorted(backends)})"
        )
    if scheme in ("tls", "wss"):
        _check_tls_configured(address)
    if scheme in ("tcp", "tls", "ws", "wss"):
        host, port = _host_port(address, loc, parse_host_port)
        try:
            socket.create_connection((host, port), timeout=timeout_s).close()
        except (OSError, UnicodeError) as exc:
            raise ConfigError(
                "--scheduler", f"cannot connect to {address}: {_reason(exc)}"
            ) from None
    elif scheme == "inproc":
        from distributed.comm.inproc import global_manager

        try:
            listener = global_manager.get_listener_for(loc)
        except (ValueError, TypeError):  # not IP/PID/N, or another process's
            listener = None
        if listener is None:
            raise ConfigError(
                "--scheduler",
                f"no scheduler listens at {address} in this process (inproc:// addresses "
                "reach only a cluster started in the same Python process)",
            )
    return scheme, loc


def _check_tls_configured(address: str) -> None:
    """Refuse a TLS address when dask has no TLS configuration for a client."""
    from distributed.security import Security

    try:
        ctx = Security().get_connection_args("client").get("ssl_context")
    except (OSError, ValueError) as exc:  # a configured file missing or unreadable
        raise ConfigError(
            "--scheduler", f"{address}: dask's TLS configuration cannot be loaded: {_reason(exc)}"
        ) from None
    if ctx is None:
        raise ConfigError(
            "--scheduler",
            f"{address} needs dask's TLS configuration, and none is set: the certificate "
            "authority and this client's certificate and key (distributed.comm.tls.ca-file, "
            ".client.cert and .client.key in a dask config file, or "
            "DASK_DISTRIBUTED__COMM__TLS__CA_FILE and the like in the environment)",
        )


def _host_port(address, loc, parse_host_port) -> tuple[str, int]:
    try:
        host, port = parse_host_port(loc)
    except ValueError as exc:
        raise ConfigError("--scheduler", f"{address!r} is not an address: {exc}") from None
    if not host or port is None or not 0 < int(port) < 65536:
        raise ConfigError("--scheduler", f"{address!r} needs a host and a port 1-65535")
    return host, int(port)


def _reason(exc: BaseException) -> str:
    return getattr(exc, "strerror", None) or str(exc) or type(exc).__name__


def _recv_exactly(sock: socket.socket, n: int, deadline: float) -> bytes:
    """``n`` bytes from ``sock`` before ``deadline`` (time.monotonic), or TimeoutError /
    ConnectionError."""
    data = b""
    while len(data) < n:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError
        sock.settimeout(left)
        part = sock.recv(n - len(data))
        if not part:
            raise ConnectionError("the connection was closed")
        data += part
    return data


def _handshake(greeting: bytes) -> dict | None:
    """The handshake table a dask comm sends first, or None when ``greeting`` (the message
    after its 8-byte length) is not one: a frame count, the frames' lengths, then one msgpack
    map with ``python`` and ``pickle-protocol``."""
    import msgpack

    if len(greeting) < 16:
        return None
    (n_frames,) = struct.unpack_from("<Q", greeting)
    if not 1 <= n_frames <= 16 or 8 * (1 + n_frames) > len(greeting):
        return None
    lengths = struct.unpack_from(f"<{n_frames}Q", greeting, 8)
    start = 8 * (1 + n_frames)
    if start + sum(lengths) != len(greeting):
        return None
    try:
        table = msgpack.unpackb(
            greeting[start : start + lengths[0]], raw=False, use_list=False, strict_map_key=False
        )
    except Exception:  # any malformed msgpack
        return None
    if not isinstance(table, dict) or not {"python", "pickle-protocol"} <= set(table):
        return None
    return table


def _our_handshake() -> bytes:
    """What a dask client sends on connecting: its own handshake, as one framed message."""
    import pickle
    import sys

    import msgpack

    body = msgpack.packb(
        {
            "compression": None,
            "python": tuple(sys.version_info)[:3],
            "pickle-protocol": pickle.HIGHEST_PROTOCOL,
        }
    )
    frames = struct.pack("<QQ", 1, len(body)) + body
    return struct.pack("<Q", len(frames)) + frames


def probe_scheduler(address: str, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Refuse a TCP address where no dask scheduler greets within ``timeout_s``.

    Reads the first message a dask server sends on accepting a connection (its handshake),
    at most :data:`GREETING_MAX_BYTES`, without allocating what its length field claims.

    Parameters
    ----------
    address : str
        A ``tcp://host:port`` (or ``host:port``) address.
    timeout_s : float
        Seconds the server has to accept and greet (s).

    Raises
    ------
    ConfigError
        On ``--scheduler``: silence, a closed connection, an HTTP reply or bytes that are not
        a dask message.
    """
    from distributed.comm.addressing import parse_address, parse_host_port

    scheme, loc = parse_address(address, strict=False)
    if scheme == "ws":
        return _probe_websocket(address, *_host_port(address, loc, parse_host_port), timeout_s)
    if scheme != "tcp":
        return
    host, port = _host_port(address, loc, parse_host_port)
    not_dask = f"{address} answers but is not a dask scheduler"
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            head = _recv_exactly(sock, 8, deadline)
            if head.startswith((b"HTTP/", b"<")):
                raise ConfigError(
                    "--scheduler",
                    f"{not_dask} (it speaks HTTP: the dashboard's port? a scheduler's default "
                    "port is 8786)",
                )
            (n,) = struct.unpack("<Q", head)
            if not 16 <= n <= GREETING_MAX_BYTES:
                raise ConfigError("--scheduler", f"{not_dask} (its first message is no handshake)")
            if _handshake(_recv_exactly(sock, n, deadline)) is None:
                raise ConfigError("--scheduler", f"{not_dask} (its first message is no handshake)")
            try:
                sock.sendall(_our_handshake())
            except OSError:
                pass  # it went away after greeting: the client will say so
    except TimeoutError:
        raise ConfigError(
            "--scheduler",
            f"{address} did not greet as a dask scheduler within {timeout_s:g} s (a server that "
            "waits for a request, e.g. HTTP, or an overloaded scheduler: --connect-timeout)",
        ) from None
    except OSError as exc:
        raise ConfigError(
            "--scheduler", f"cannot connect to {address}: {_reason(exc)} (not a dask scheduler?)"
        ) from None


def _probe_websocket(address: str, host: str, port: int, timeout_s: float) -> None:
    """Refuse a ``ws://`` address whose server does not grant a WebSocket upgrade on ``/`` (what
    a dask client asks for, RFC 6455 section 4.1) within ``timeout_s``."""
    import base64
    import os

    key = base64.b64encode(os.urandom(16)).decode()
    request = (
        f"GET / HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
        f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n"
    ).encode()
    not_ws = f"{address} answers but is not a WebSocket dask scheduler"
    deadline = time.monotonic() + timeout_s
    try:
        with socket.create_connection((host, port), timeout=timeout_s) as sock:
            sock.sendall(request)
            head = _recv_exactly(sock, 8, deadline)
            if head.startswith(b"HTTP/"):  # its status code follows
                head += _recv_exactly(sock, 4, deadline)
    except TimeoutError:
        raise ConfigError(
            "--scheduler",
            f"{address} did not answer a WebSocket upgrade within {timeout_s:g} s (not a "
            "WebSocket scheduler, or an overloaded one: --connect-timeout)",
        ) from None
    except OSError as exc:
        raise ConfigError(
            "--scheduler", f"cannot connect to {address}: {_reason(exc)} (not a dask scheduler?)"
        ) from None
    if head.startswith((b"HTTP/1.1 101", b"HTTP/1.0 101")):
        return
    if head.startswith(b"HTTP/"):
        status = head[9:12].decode("ascii", "replace")
        raise ConfigError(
            "--scheduler", f"{not_ws} (it answers HTTP {status}, no upgrade: a dashboard?)"
        )
    if 16 <= struct.unpack("<Q", head[:8])[0] <= GREETING_MAX_BYTES:
        raise ConfigError(
            "--scheduler", f"{not_ws} (it greets as a TCP dask scheduler: use tcp://{host}:{port})"
        )
    raise ConfigError("--scheduler", f"{not_ws} (its answer is no HTTP)")


def connect(address, timeout_s: float = CONNECT_TIMEOUT_S):
    """A ``dask.distributed.Client`` connected to ``address``, or a one-line ConfigError.

    Parameters
    ----------
    address : str
        The scheduler's address.
    timeout_s : float
        Seconds to connect (s): the port's answer, the scheduler's greeting and the client's
        own start each within it. Default 10 s.

    Returns
    -------
    dask.distributed.Client
        Not set as dask's default client; close it when done.

    Raises
    ------
    ConfigError
        On ``--scheduler`` (or ``--connect-timeout``), naming the problem. No client is left
        behind: a client that failed to start is closed here, so its finaliser neither waits
        nor prints.
    """
    timeout_s = check_number(timeout_s, "--connect-timeout", lo=0.1)
    try:
        cls = _quiet_client_class()
    except ImportError:
        raise ConfigError(
            "--scheduler", "needs dask.distributed: pip install 'imdrive[dask]'"
        ) from None
    check_scheduler_address(address, min(timeout_s, PROBE_TIMEOUT_S))
    probe_scheduler(address, timeout_s)
    client = cls.__new__(cls)
    try:
        client.__init__(address, timeout=timeout_s, set_as_default=False)
    except Exception as exc:
        _close_quietly(client)
        first = str(exc).splitlines()[0][:200] if str(exc) else type(exc).__name__
        raise ConfigError("--scheduler", f"cannot connect to {address}: {first}") from None
    except MemoryError:
        _close_quietly(client)
        raise ConfigError(
            "--scheduler", f"{address} sent a message too large to be a dask scheduler's"
        ) from None
    return client


@functools.cache
def _quiet_client_class():
    from dask.distributed import Client

    class QuietClient(Client):
        """A client whose finaliser does not wait for, or print about, a failed start."""

        def __del__(self):
            _close_quietly(self)

    return QuietClient


def _close_quietly(client) -> None:
    """Close a client that may never have started, briefly and without a word."""
    try:
        if getattr(client, "status", "newly-created") not in ("closed", "newly-created"):
            client.close(timeout=2)
    except Exception:  # a client half made, a scheduler gone: nothing to close
        pass
