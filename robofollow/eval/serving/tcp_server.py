"""`robofollow serve --protocol tcp`: a Python policy behind upstream RoboFollow's TCP
protocol (protocols/tcp_protocol.py), each connection in its own thread with its own policy
instance.

Error replies carry the error's message; "traceback" says only that the traceback is in the
server's log. A message over the server's limit is answered with an error and the connection
closed. The server also answers an HTTP `GET /healthz` on its port with 200, checks each
predict observation against the layout it declares on reset ("robofollow": {"observation":
...}), and resets its policy for each connection.
"""

from __future__ import annotations

import socket
import threading
import time

from robofollow.benchmark.episode import Benchmark
from robofollow.eval.protocols.limits import DEFAULT_HOST
from robofollow.eval.protocols.tcp_protocol import (
    CAMERAS,
    receive_message,
    send_message,
)
from robofollow.eval.protocols.wire import MessageTooBig, WireError, server_text
from robofollow.eval.serving.serving import (
    PolicyPool,
    RequestError,
    ServerBusyError,
    ServerLimits,
    checked_images,
    error_reply,
    log,
)

TRACEBACK_NOTE = "not sent; see the server's log"


def _drain(connection: socket.socket, limit: int = 2 ** 20, seconds: float = 1.0) -> None:
    """Close our side, then read (and drop) what the client still sends for a moment, so
    that the reply just sent is not lost to a reset of a connection with unread data."""
    try:
        connection.shutdown(socket.SHUT_WR)
        connection.settimeout(seconds)
        deadline, read = time.monotonic() + seconds, 0
        while read < limit and time.monotonic() < deadline:
            chunk = connection.recv(65536)
            if not chunk:
                return
            read += len(chunk)
    except OSError:
        pass


HTTP_REQUEST_LIMIT = 8192  # bytes of an HTTP request's head read for a health check


def _answer_http(connection: socket.socket) -> None:
    """A health check on the server's port: `GET /healthz` is 200, any other path 404."""
    head = b""
    while b"\r\n\r\n" not in head and len(head) < HTTP_REQUEST_LIMIT:
        chunk = connection.recv(HTTP_REQUEST_LIMIT - len(head))
        if not chunk:
            break
        head += chunk
    path = head.split(b"\r\n", 1)[0].split(b" ")[1:2]
    status, body = ("200 OK", b"OK\n") if path == [b"/healthz"] else \
        ("404 Not Found", b"this port speaks RoboFollow's TCP protocol; GET /healthz checks it\n")
    connection.sendall(f"HTTP/1.1 {status}\r\nContent-Type: text/plain\r\nContent-Length: "
                       f"{len(body)}\r\nConnection: close\r\n\r\n".encode() + body)


class _Session:
    """One connection's state: its policy instance and the instruction last set."""

    def __init__(self, pool: PolicyPool):
        self.pool, self.served, self.instruction = pool, None, ""

    def answer(self, request):
        if not isinstance(request, dict):
            raise RequestError("a request must be {'cmd': ..., 'obs': ...}")
        command, obs = request.get("cmd"), request.get("obs")
        if command not in ("reset", "set_instruction", "predict"):
            raise RequestError(f"unknown command {server_text(repr(command))} (expected reset, "
                               "set_instruction or predict)")
        if self.served is None:
            self.served = self.pool.acquire()
        if command == "reset":
            self.served.reset()
            self.instruction = ""
            return self.served.metadata(channels_first=False)
        if command == "set_instruction":
            if not isinstance(obs, str):
                raise RequestError("set_instruction's obs must be the instruction string")
            self.instruction = obs
            return None
        if not isinstance(obs, dict) or not isinstance(obs.get("joint_action"), dict):
            raise RequestError("predict's obs must be {'observation', 'joint_action': "
                               "{'vector'}, 'instruction'}")
        cameras = obs.get("observation") or {}
        if not isinstance(cameras, dict) or not all(
                isinstance(cameras[key], dict) for key in CAMERAS.values() if key in cameras):
            raise RequestError("predict's 'observation' must map head_camera, left_camera and "
                               "right_camera to {'rgb': array}")
        images = {name: cameras[key].get("rgb") for name, key in CAMERAS.items()
                  if key in cameras} or None
        if images is not None and "images" in self.pool.uses:
            images = checked_images(images, channels_first=False, names=CAMERAS,
                                    where="predict's 'observation'")
        return self.served.act(obs["joint_action"].get("vector"),
                               obs.get("instruction", self.instruction), images,
                               obs.get("privileged"), obs.get("step"), obs.get("objects"))

    def close(self) -> None:
        if self.served is not None:
            self.pool.release(self.served)
            self.served = None


class TcpPolicyServer:
    """Serves one Python policy over upstream's TCP protocol, each connection in a thread."""

    def __init__(self, compiled: Benchmark, policy_spec: str,
                 limits: ServerLimits | None = None):
        self.limits = limits or ServerLimits()
        self.pool = PolicyPool(compiled, policy_spec, self.limits.max_clients)
        self.stopped = threading.Event()
        self.slots = threading.BoundedSemaphore(self.limits.max_clients)

    def handle(self, connection: socket.socket, peer="client") -> None:
        """Answer one connection's requests until it closes, idles past the time-out, sends
        a message over the limit or bytes that are not the protocol; or, for an HTTP
        request, its health check."""
        session = _Session(self.pool)
        with connection:
            connection.settimeout(self.limits.idle_timeout)
            try:
                if connection.recv(4, socket.MSG_PEEK | socket.MSG_WAITALL) == b"GET ":
                    _answer_http(connection)
                    return
                while not self.stopped.is_set():
                    try:
                        request = receive_message(connection, self.limits.max_message)
                    except (MessageTooBig, WireError) as error:  # refused, then closed
                        log.warning("%s: %s", peer, error)
                        send_message(connection, {"error": f"{type(error).__name__}: {error}",
                                                  "traceback": TRACEBACK_NOTE})
                        _drain(connection)
                        return
                    try:
                        reply = {"res": session.answer(request)}
                    except Exception as error:  # the message only; the traceback is logged
                        reply = {"error": error_reply(error, str(peer)),
                                 "traceback": TRACEBACK_NOTE}
                    try:
                        send_message(connection, reply)
                    except (TypeError, ValueError) as error:  # a reply JSON cannot carry
                        send_message(connection, {"error": error_reply(error, str(peer)),
                                                  "traceback": TRACEBACK_NOTE})
            except OSError:  # closed, reset, or idle past the time-out
                return
            except Exception:  # never the server: only this connection ends
                log.exception("%s: connection failed", peer)
            finally:
                session.close()

    def serve_forever(self, host: str = DEFAULT_HOST, port: int = 0, ready=None) -> None:
        """Serve until `shutdown()`; `ready(listening socket)` once clients can connect."""
        with socket.create_server((host, port)) as listener:
            listener.settimeout(0.5)  # to notice shutdown()
            if ready is not None:
                ready(listener)
            while not self.stopped.is_set():
                try:
                    connection, peer = listener.accept()
                except TimeoutError:
                    continue
                if not self.slots.acquire(blocking=False):  # refused, not queued
                    self._refuse(connection, peer)
                    continue
                threading.Thread(target=self._serve_one, args=(connection, peer), daemon=True,
                                 name=f"robofollow-tcp-{peer}").start()

    def _serve_one(self, connection: socket.socket, peer) -> None:
        try:
            self.handle(connection, peer)
        finally:
            self.slots.release()

    def _refuse(self, connection: socket.socket, peer) -> None:
        with connection:
            error = ServerBusyError(f"the server is serving its limit of "
                                    f"{self.limits.max_clients} clients; try again later")
            try:
                connection.settimeout(1.0)
                send_message(connection, {"error": error_reply(error, str(peer)),
                                          "traceback": TRACEBACK_NOTE})
            except OSError:
                pass

    def shutdown(self) -> None:
        """Stop accepting; open connections end at their next message."""
        self.stopped.set()
