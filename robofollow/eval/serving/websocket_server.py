"""`robofollow serve`: a Python policy behind the openpi websocket protocol (described in
robofollow.eval.policies.websocket_client), each connection in its own thread with its own policy
instance.

A failed request is answered with a text message, the error's type and message only (the
traceback goes to the server's log), and the connection closed. The server also answers
`GET /healthz` with 200 (as openpi's server does), checks each observation against the layout
its metadata declares ("robofollow": {"observation": ...}), and resets its policy for each
connection.
"""

from __future__ import annotations

import http

from websockets.exceptions import ConnectionClosed
from websockets.frames import CloseCode
from websockets.sync.server import serve

from robofollow.benchmark.episode import Benchmark
from robofollow.eval.protocols.limits import DEFAULT_HOST
from robofollow.eval.protocols.wire import WireError, packb, unpackb
from robofollow.eval.serving.serving import (
    PolicyPool,
    RequestError,
    ServerLimits,
    checked_images,
    error_reply,
    log,
)


def _health(connection, request):
    """`GET /healthz` is answered 200 without a websocket handshake; other paths go on."""
    if request.path == "/healthz":
        return connection.respond(http.HTTPStatus.OK, "OK\n")
    return None


def _peer(connection) -> str:
    """The client's address as the log names it; "client" for one already gone (its socket
    closed: a client that drops right after the handshake has no address left to ask)."""
    try:
        return str(connection.remote_address)
    except OSError:
        return "client"


class PolicyServer:
    """Serves one Python policy; each connection in its own thread with its own policy
    instance, at most `limits.max_clients` at once."""

    def __init__(self, compiled: Benchmark, policy_spec: str,
                 limits: ServerLimits | None = None):
        self.limits = limits or ServerLimits()
        self.pool = PolicyPool(compiled, policy_spec, self.limits.max_clients)
        self.server = None

    def handle(self, connection) -> None:
        peer = _peer(connection)
        try:
            served = self.pool.acquire()
        except Exception as error:  # busy
            self._fail(connection, error_reply(error, peer))
            return
        try:
            connection.send(packb(self.pool.metadata(channels_first=True)))
            while True:
                try:
                    data = connection.recv(timeout=self.limits.idle_timeout)
                except TimeoutError:
                    log.warning("%s: idle for %s s; closed", peer, self.limits.idle_timeout)
                    connection.close(CloseCode.GOING_AWAY, "idle")
                    return
                try:
                    message = unpackb(data)
                    if not isinstance(message, dict):
                        raise RequestError("an observation must be a map")
                    if message.get("reset"):
                        served.reset()
                        connection.send(packb({"reset": True}))
                        continue
                    if "state" not in message:
                        raise RequestError("the observation has no 'state'")
                    images = message.get("images")
                    if images is not None and "images" in self.pool.uses:
                        images = checked_images(images, channels_first=True)
                    actions = served.act(message["state"], message.get("prompt", ""), images,
                                         message.get("privileged"), message.get("step"),
                                         message.get("objects"))
                    reply = packb({"actions": actions})
                except Exception as error:  # openpi's way: a text message, then close
                    if isinstance(error, WireError):
                        error = RequestError(str(error))
                    self._fail(connection, error_reply(error, peer))
                    return
                connection.send(reply)
        except ConnectionClosed:  # the client left, or sent a message over the limit
            return
        except Exception:  # never the server: only this connection ends
            log.exception("%s: connection failed", peer)
        finally:
            self.pool.release(served)

    @staticmethod
    def _fail(connection, text: str) -> None:
        try:
            connection.send(text)
            connection.close(CloseCode.INTERNAL_ERROR, "error")
        except ConnectionClosed:
            pass

    def serve_forever(self, host: str = DEFAULT_HOST, port: int = 0, ready=None) -> None:
        """Serve until `shutdown()`; `ready(listening socket)` once clients can connect."""
        with serve(self.handle, host, port, compression=None, max_size=self.limits.max_message,
                   open_timeout=min(10.0, self.limits.idle_timeout),
                   process_request=_health) as server:
            self.server = server
            if ready is not None:
                ready(server.socket)
            server.serve_forever()

    def shutdown(self) -> None:
        if self.server is not None:
            self.server.shutdown()
