"""An existing dask scheduler, checked before use and never waited for without a limit.

A wrong scheduler must not hang a run: ``distributed.Client(scheduler_file=...)`` waits
for a missing file without end, a host that silently drops packets keeps a TCP connect
waiting for minutes, and a scheduler without workers accepts tasks that never run. Here:

* a scheduler file (``*.json``, written by ``dask scheduler --scheduler-file F``) must
  exist and hold the scheduler's ``address``;
* a ``tcp://HOST:PORT`` address must accept a TCP connection and send the dask
  handshake within :data:`CONNECT_TIMEOUT_S` (:func:`check_scheduler`, cheap: the CLI
  calls it before any work starts; a peer that accepts and stays silent would otherwise
  keep ``distributed.Client`` waiting without end, its own timeout notwithstanding);
* :func:`connect_client` then connects under a hard limit (a thread, 3 times that) and
  waits at most :data:`CONNECT_TIMEOUT_S` for a first worker.

Every failure is a ``ConnectionError`` (an ``OSError``) with one line naming the
scheduler and what is wrong.
"""
from __future__ import annotations

import json
import socket
import threading
from pathlib import Path

__all__ = ["CONNECT_TIMEOUT_S", "check_scheduler", "connect_client", "scheduler_address"]

#: Seconds to reach a scheduler and to wait for its first worker: a scheduler on a
#: reachable network answers in milliseconds, so a few seconds separate "slow" from "not
#: there" without letting a wrong address hang a run.
CONNECT_TIMEOUT_S = 10.0


def scheduler_address(target: str) -> str:
    """The address of ``target``: itself, or the ``address`` in a scheduler file."""
    if not target.endswith(".json"):
        return target
    path = Path(target)
    if not path.is_file():
        raise ConnectionError(f"scheduler file {target} does not exist (start the scheduler "
                              f"with `dask scheduler --scheduler-file {target}`)")
    try:
        info = json.loads(path.read_text(encoding="utf-8"))
        address = info["address"]
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as exc:
        raise ConnectionError(f"scheduler file {target} is not a dask scheduler file "
                              f"(no readable 'address': {exc.__class__.__name__})") from None
    if not isinstance(address, str) or "://" not in address:
        raise ConnectionError(f"scheduler file {target}: 'address' must read "
                              f"PROTOCOL://HOST:PORT, got {address!r}")
    return address


def _host_port(address: str):
    """(host, port) of a TCP address (``tcp://H:P`` or ``H:P``), None for others."""
    proto, _, rest = address.rpartition("://")
    if proto not in ("", "tcp", "tls"):
        return None
    host, _, port = rest.rpartition(":")
    host = host.strip("[]")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConnectionError(f"dask scheduler address {address!r} must read "
                              "tcp://HOST:PORT with a port in 1-65535")
    return host, int(port)


def check_scheduler(target: str, timeout: float = CONNECT_TIMEOUT_S) -> str:
    """Check that the scheduler ``target`` (address or file) can be reached; its address.

    Raises
    ------
    ConnectionError
        One line: missing or malformed file, bad address, refused or timed-out connect.
    """
    address = scheduler_address(target)
    hp = _host_port(address)
    if hp is None:
        return address
    try:
        with socket.create_connection(hp, timeout=timeout) as sock:
            # a dask scheduler sends its handshake (msgpack, key "compression") as soon as
            # it accepts; a peer that stays silent would keep distributed waiting forever
            greeting = b"" if address.startswith("tls://") else _first_bytes(sock, timeout)
    except socket.timeout:
        raise ConnectionError(f"dask scheduler at {address}: no answer within "
                              f"{timeout:g} s") from None
    except OSError as exc:
        raise ConnectionError(f"dask scheduler at {address}: cannot connect "
                              f"({exc.strerror or exc})") from None
    if not address.startswith("tls://") and b"compression" not in greeting:
        raise ConnectionError(f"dask scheduler at {address}: the peer does not speak the "
                              "dask protocol (no handshake)")
    return address


def _first_bytes(sock, timeout: float, size: int = 256) -> bytes:
    """What the peer sends first, within ``timeout`` seconds (socket.timeout if nothing)."""
    import time

    sock.settimeout(timeout)
    data, end = b"", time.monotonic() + timeout
    while b"compression" not in data and len(data) < size:
        sock.settimeout(max(end - time.monotonic(), 1e-3))
        try:
            chunk = sock.recv(size)
        except socket.timeout:
            if data:
                break
            raise
        if not chunk:
            break
        data += chunk
    return data


def connect_client(target: str, timeout: float = CONNECT_TIMEOUT_S):
    """A ``distributed.Client`` of the scheduler ``target`` that has at least one worker."""
    from distributed import Client

    address = check_scheduler(target, timeout)
    result = {}

    def connect():
        try:
            result["client"] = Client(address, timeout=f"{timeout:g}s")
        except Exception as exc:  # timeouts, refused, garbage from a non-dask peer
            result["error"] = exc

    # distributed's own timeout does not bound every wait of its handshake: a hard limit
    worker = threading.Thread(target=connect, name="iwanfe-dask-connect", daemon=True)
    worker.start()
    worker.join(3 * timeout)
    if "client" not in result:
        exc = result.get("error")
        why = (f"{exc.__class__.__name__}: {str(exc)[:120]}" if exc is not None
               else f"no connection after {3 * timeout:g} s")
        raise ConnectionError(f"dask scheduler at {address}: no dask handshake ({why})")
    client = result["client"]
    try:
        client.wait_for_workers(1, timeout=timeout)
    except Exception:
        client.close()
        raise ConnectionError(f"dask scheduler at {address} has no worker after {timeout:g} s "
                              f"(start one: `dask worker {address}`)") from None
    return client
