"""Shared set-up for the policy-server tests: upstream's TCP framing written by hand, a
`robofollow serve` server in a thread and a raw client of it."""

from __future__ import annotations

import base64
import json
import socket
import struct
import threading
from contextlib import contextmanager

import numpy as np

WAIT = 10.0  # seconds: the longest any step of these tests may wait


def _frame(message) -> bytes:
    payload = json.dumps(message).encode()
    return struct.pack(">I", len(payload)) + payload


def _read(connection: socket.socket):
    """One length-prefixed JSON message, or None when the peer closed."""
    header = connection.recv(4, socket.MSG_WAITALL)
    if len(header) < 4:
        return None
    (size,) = struct.unpack(">I", header)
    return json.loads(connection.recv(size, socket.MSG_WAITALL))


def _array(data: np.ndarray) -> dict:
    return {"__numpy_array__": True, "data": base64.b64encode(data.tobytes()).decode(),
            "dtype": data.dtype.str, "shape": list(data.shape)}


@contextmanager
def served(server):
    """One of `robofollow serve`'s servers (TcpPolicyServer or PolicyServer) in a thread."""
    holder, ready = {}, threading.Event()

    def on_ready(listening):
        sock = listening if isinstance(listening, socket.socket) else listening.socket
        holder["port"] = sock.getsockname()[1]
        ready.set()

    threading.Thread(target=server.serve_forever, args=("127.0.0.1", 0, on_ready),
                     daemon=True).start()
    assert ready.wait(WAIT)
    try:
        yield holder["port"]
    finally:
        server.shutdown()


def _client(port: int) -> socket.socket:
    connection = socket.create_connection(("127.0.0.1", port), timeout=WAIT)
    connection.settimeout(WAIT)
    return connection
