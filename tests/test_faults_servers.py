"""Fault injection for the policy servers and clients, and the reports they feed: hostile
servers (garbage, oversize replies, silence, lost connections, bad metadata, a non-HTTP
handshake, invalid actions), hostile clients against `robofollow serve`'s servers (oversize,
idle and malformed requests, clients that drop at once), the default bind address, HTML escaping in report.html, and
privileged observations sent only with --allow-privileged and recorded then.

Every wait has a time limit (socket time-outs, subprocess and event waits), so a hang fails
the test instead of stalling the suite."""

from __future__ import annotations

import json
import logging
import re
import select
import selectors
import socket
import struct
import threading
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect
from websockets.sync.server import serve

from robofollow.cli import main, parser
from robofollow.eval.policies.loading import PolicyLoadError, load_policy
from robofollow.eval.policies.policy import (
    BadActionError,
    PolicyConnectionError,
    PolicyServerError,
    PrivilegedRefusedError,
    validate_actions,
)
from robofollow.eval.policies.tcp_client import TcpPolicy
from robofollow.eval.policies.websocket_client import WebsocketPolicy
from robofollow.eval.protocols.limits import (
    IDLE_TIMEOUT_S,
    MAX_CLIENTS,
    MAX_MESSAGE_BYTES,
)
from robofollow.eval.protocols.wire import packb, unpackb
from robofollow.eval.reports.report import write_report
from robofollow.eval.running.episode import run_episode
from robofollow.eval.running.runner import EvalOptions
from robofollow.eval.serving.serving import ServerLimits
from robofollow.eval.serving.tcp_server import TcpPolicyServer
from robofollow.eval.serving.websocket_server import PolicyServer
from robofollow.resources import builtin_specs
from robofollow.sim import robot
from tests.server_helpers import WAIT, _array, _client, _frame, _read, served
from tests.sim_helpers import benchmark, episode, serve_process

HOME = robot.home_state()
EPISODE = "scene2/L0/pickup_left_cube#r1"


# -- helpers: hostile servers -----------------------------------------------------------------

def _no_traceback(text: str) -> None:
    assert "Traceback" not in text and not re.search(r'File ".*\.py"', text), text


@contextmanager
def raw_server(respond):
    """A TCP server calling `respond(connection)` for each connection (in a thread); yields
    its port and the list of connections accepted."""
    listener = socket.create_server(("127.0.0.1", 0))
    listener.settimeout(WAIT)
    accepted: list = []

    def run():
        while True:
            try:
                connection, _ = listener.accept()
            except OSError:
                return
            connection.settimeout(WAIT)
            accepted.append(connection)
            threading.Thread(target=_quietly, args=(respond, connection), daemon=True).start()

    threading.Thread(target=run, daemon=True).start()
    try:
        yield listener.getsockname()[1], accepted
    finally:
        listener.close()
        for connection in accepted:
            connection.close()


def _quietly(respond, connection) -> None:
    try:
        respond(connection)
    except OSError:
        pass


def _silent_until_closed(closed: threading.Semaphore):
    """A responder that reads what it is sent and never answers; `closed` is released when
    the client closes the connection (not when this end's time-out ends it)."""
    def respond(connection):
        while connection.recv(1 << 20):
            pass
        closed.release()
    return respond


def _closed_by_peer(connection: socket.socket) -> bool:
    """Whether the peer has closed `connection` (checked without waiting)."""
    readable, _, _ = select.select([connection], [], [], 0)
    return bool(readable) and connection.recv(1, socket.MSG_PEEK) == b""


@contextmanager
def ws_server(handler):
    """An openpi-style websocket server with no size limit of its own."""
    holder, ready = {}, threading.Event()

    def run():
        with serve(handler, "127.0.0.1", 0, compression=None, max_size=None) as server:
            holder["server"] = server
            ready.set()
            server.serve_forever()

    threading.Thread(target=run, daemon=True).start()
    assert ready.wait(WAIT)
    try:
        yield f"ws://127.0.0.1:{holder['server'].socket.getsockname()[1]}"
    finally:
        holder["server"].shutdown()


def _predict(state=HOME) -> dict:
    return {"cmd": "predict", "obs": {"observation": {}, "instruction": "stay",
                                      "joint_action": {"vector": _array(state)}}}


# -- hostile TCP servers ----------------------------------------------------------------------

def _answers(data: bytes):
    def respond(connection):
        while connection.recv(4, socket.MSG_WAITALL):  # whatever is asked
            connection.recv(1 << 20)
            connection.sendall(data)
    return respond


@pytest.mark.parametrize("data, message", [
    (struct.pack(">I", 11) + b"not json!!!", "not upstream's protocol: not JSON"),
    (b"HTTP/1.1 400 Bad Request\r\n\r\n", r"over the limit of 16777216 bytes"),
    (_frame([1, 2, 3]), r"with \[1, 2, 3\], not \{'res'"),
    (_frame({"res": {"__numpy_array__": True, "data": "AAAA", "dtype": "|O", "shape": [1]}}),
     "dtype object are refused"),
    (_frame({"res": {"__numpy_array__": True, "data": "AAAA", "dtype": "<f8", "shape": [9]}}),
     "does not hold 3 bytes"),
    (struct.pack(">I", 50_000) + b"[" * 50_000, "not JSON: RecursionError"),
], ids=["not-json", "http", "list", "object-array", "short-array", "deep"])
def test_a_tcp_server_sending_garbage_is_a_clear_failure_not_retried(data, message):
    with raw_server(_answers(data)) as (port, accepted):
        policy = TcpPolicy("127.0.0.1", port, timeout=3, retries=3)
        with pytest.raises(PolicyServerError, match=message):
            policy.reset()
        assert len(accepted) == 1  # a server speaking something else is not asked again


def test_an_oversize_tcp_reply_is_refused_unread_at_the_default_and_a_configured_limit():
    closed = threading.Event()

    def huge(connection):
        connection.recv(1 << 20)
        connection.sendall(struct.pack(">I", MAX_MESSAGE_BYTES + 1) + b"x" * 1000)
        try:  # the rest never comes: the client must close without waiting for it
            connection.recv(1)
        except ConnectionResetError:  # (closed with the 1000 bytes unread)
            pass
        closed.set()

    with raw_server(huge) as (port, _):
        with pytest.raises(PolicyServerError, match=r"a message of 16777217 bytes \(16\.0 MiB\) "
                                                    "is over the limit"):
            TcpPolicy("127.0.0.1", port, timeout=3, retries=0).reset()
        assert closed.wait(WAIT)
    reply = _frame({"res": _array(np.zeros((50, 14)))})  # ~7.6 kB
    with raw_server(_answers(reply)) as (port, _):
        policy = load_policy(f"tcp://127.0.0.1:{port}?max_message=4000")
        with pytest.raises(PolicyServerError, match="over the limit of 4000 bytes.*max_message"):
            policy.reset()
        load_policy(f"tcp://127.0.0.1:{port}?max_message=9000").reset()  # within it


def test_a_silent_tcp_server_times_out_and_a_closing_one_is_retried_then_reported():
    closed = threading.Semaphore(0)
    with raw_server(_silent_until_closed(closed)) as (port, accepted):
        with pytest.raises(PolicyConnectionError, match="did not answer 'reset' after 2 tries"):
            TcpPolicy("127.0.0.1", port, timeout=0.3, retries=1).reset()
        assert all(closed.acquire(timeout=WAIT) for _ in range(2)) and len(accepted) == 2
    with raw_server(lambda connection: connection.close()) as (port, accepted):
        with pytest.raises(PolicyConnectionError, match="after 3 tries"):
            TcpPolicy("127.0.0.1", port, timeout=1, retries=2).reset()


def test_a_server_error_text_is_quoted_short_and_on_one_line():
    with raw_server(_answers(_frame({"error": "boom\n" + "x" * 100_000}))) as (port, _):
        with pytest.raises(PolicyServerError) as failure:
            TcpPolicy("127.0.0.1", port, timeout=WAIT).reset()
    assert len(str(failure.value)) < 700 and "\n" not in str(failure.value)


# -- invalid actions -------------------------------------------------------------------------

@pytest.mark.parametrize("actions, message", [
    ([["0.5"] * 14], "got strings"),
    (np.full((2, 14), 0.1 + 2j), "got complex numbers"),
    (np.ones((2, 14), bool), "got booleans"),
    ([[0.1] * 13 + [[0.2]]], "actions are not numbers"),  # nested garbage
    ([[0.1] * 13 + [None]], "got objects"),
    ([[10 ** 400] * 14], "got objects"),
    ({"a": 1}, "got objects"),
    (None, "got objects"),
    (np.zeros(14)[None, :, None], r"got shape \[1, 14, 1\]"),
])
def test_actions_must_be_real_finite_numbers_of_the_declared_shape(actions, message):
    with pytest.raises(BadActionError, match=message):
        validate_actions(actions)


@pytest.mark.parametrize("res, message", [
    ([["0.5"] * 14], "got strings"),
    (_array(np.full((1, 14), 1 + 1j)), "got complex numbers"),
    ([[True] * 14], "got booleans"),
    ([[0.1] * 13 + [{"x": 1}]], "got objects"),
])
def test_actions_from_a_server_are_validated_not_converted(res, message):
    with raw_server(_answers(_frame({"res": res}))) as (port, _):
        policy = TcpPolicy("127.0.0.1", port, timeout=WAIT)
        answer = policy.act({"state": HOME, "instruction": "x"})
        policy.close()
    with pytest.raises(BadActionError, match=message):
        validate_actions(answer)


# -- hostile websocket servers ---------------------------------------------------------------

def _sends_metadata(data):
    def handler(connection):
        connection.send(data)
        for _ in connection:
            pass
    return handler


@pytest.mark.parametrize("metadata, error, message", [
    (b"\xc1\xc1\xc1", PolicyServerError, "metadata that is not msgpack-numpy"),
    ("Traceback (most recent call last): boom", PolicyServerError, "failed: Traceback"),
    (packb([1, 2]), PolicyServerError, r"metadata that is not a map: \[1, 2\]"),
    (packb({"robofollow": 5}), PolicyServerError, "malformed metadata"),
    (packb({"robofollow": {"uses": "images"}}), PolicyServerError, "malformed metadata"),
    (packb({"robofollow": {"uses": ["telepathy"]}}), PolicyServerError, "unknown observation"),
    (packb({"robofollow": {"uses": ["privileged"]}}), PrivilegedRefusedError,
     "--allow-privileged"),
], ids=["garbage", "text", "list", "not-a-map", "uses-str", "unknown-part", "privileged"])
def test_bad_metadata_is_a_clear_error_at_load(metadata, error, message):
    with ws_server(_sends_metadata(metadata)) as uri:
        with pytest.raises(error, match=message):
            load_policy(uri + "?timeout=5")


def test_bad_metadata_is_an_error_line_from_the_cli_not_a_traceback(tmp_path, capsys):
    with ws_server(_sends_metadata(packb({"robofollow": {"uses": 7}}))) as uri:
        code = main(["eval", "--policy", uri, "--out", str(tmp_path / "run"), "--specs",
                     str(builtin_specs()), "--tasks", "scene2/L0/pickup_left_cube",
                     "--rounds", "1", "--workers", "1", "--quiet"])
    err = capsys.readouterr().err
    assert code == 1 and "malformed metadata" in err
    _no_traceback(err)


def test_a_non_http_handshake_is_a_connection_error():
    def ssh(connection):
        connection.recv(1 << 16)
        connection.sendall(b"SSH-2.0-OpenSSH_9.6\r\n")
        connection.close()

    with raw_server(ssh) as (port, _):
        with pytest.raises(PolicyConnectionError, match="cannot reach.*(HTTP|Invalid)"):
            load_policy(f"ws://127.0.0.1:{port}?timeout=5")
    closed = threading.Semaphore(0)
    with raw_server(_silent_until_closed(closed)) as (port, _):  # says nothing
        with pytest.raises(PolicyConnectionError, match="cannot reach"):
            WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=0.5)
        assert closed.acquire(timeout=WAIT)


def test_an_oversize_websocket_reply_is_refused_and_not_retried():
    connections = []

    def huge(connection):
        connections.append(connection)
        connection.send(packb({}))
        for _ in connection:
            connection.send(packb({"actions": np.zeros((MAX_MESSAGE_BYTES // 8 + 1,))}))

    with ws_server(huge) as uri:
        policy = WebsocketPolicy(uri, timeout=WAIT, retries=3)
        with pytest.raises(PolicyServerError, match="over this client's limit of 16777216"):
            policy.act({"state": HOME, "instruction": "x"})
        small = load_policy(uri + "?max_message=100000&retries=3")
        assert small.max_message == 100_000
        with pytest.raises(PolicyServerError, match="limit of 100000 bytes.*max_message"):
            small.act({"state": HOME, "instruction": "x"})
    assert len(connections) == 2  # one each: never retried


def test_a_silent_websocket_server_times_out():
    closed = threading.Event()

    def silent(connection):
        connection.send(packb({}))
        try:
            while True:
                connection.recv(timeout=WAIT)
        except ConnectionClosed:  # by the client, not by this end's time-out
            closed.set()

    with ws_server(silent) as uri:
        policy = WebsocketPolicy(uri, timeout=0.3, retries=0)
        with pytest.raises(PolicyConnectionError, match="did not answer after 1 tries"):
            policy.act({"state": HOME, "instruction": "x"})
        assert closed.wait(WAIT)


def test_a_server_lost_mid_episode_ends_that_episode_with_the_reason(stage):
    answered = []

    def once(connection):
        connection.send(packb({}))
        if answered:  # gone for good after its first chunk
            return
        obs = unpackb(connection.recv(timeout=WAIT))
        answered.append(True)
        connection.send(packb({"actions": np.repeat(obs["state"][None], 50, axis=0)}))
        connection.recv(timeout=WAIT)

    with ws_server(once) as uri:
        policy = load_policy(uri + "?timeout=2&retries=1")
        run = run_episode(benchmark(), stage, episode(EPISODE), policy, budget=150)
        policy.close()
    assert run.steps == 50 and "PolicyConnectionError" in run.error


# -- hostile clients against `robofollow serve`'s servers ------------------------------------

def test_the_tcp_server_refuses_an_oversize_request_and_goes_on_serving():
    server = TcpPolicyServer(benchmark(), "noop", ServerLimits(max_message=2000))
    with served(server) as port:
        with _client(port) as connection:
            connection.sendall(struct.pack(">I", 10 ** 9) + b"x" * 100)
            reply = _read(connection)
            assert "over the limit of 2000 bytes" in reply["error"]
            _no_traceback(json.dumps(reply))
            assert _read(connection) is None  # then closed
        with _client(port) as connection:
            connection.sendall(_frame({"cmd": "reset", "obs": None}))
            assert _read(connection)["res"]["robofollow"]["uses"] == []


def test_an_idle_tcp_client_does_not_block_another_and_is_closed_after_its_time_out():
    server = TcpPolicyServer(benchmark(), "noop", ServerLimits(idle_timeout=2.0))
    with served(server) as port:
        idle = _client(port)
        idle.sendall(b"\x00\x00")  # half a header, then nothing
        with _client(port) as busy:
            busy.sendall(_frame({"cmd": "reset", "obs": None}))
            assert "res" in _read(busy)
            busy.sendall(_frame(_predict()))
            assert _read(busy)["res"]["shape"] == [50, 14]
        assert not _closed_by_peer(idle)  # served while the idle one waits
        assert idle.recv(16) == b""  # closed by the server, not by this test's time-out
        idle.close()


def test_the_tcp_server_serves_at_most_its_clients_and_refuses_more():
    server = TcpPolicyServer(benchmark(), "noop", ServerLimits(max_clients=1))
    with served(server) as port:
        with _client(port) as first, _client(port) as second:
            reply = _read(second)
            assert "limit of 1 clients" in reply["error"] and _read(second) is None
            first.sendall(_frame({"cmd": "reset", "obs": None}))
            assert "res" in _read(first)


@pytest.mark.parametrize("payload, closes, message", [
    (b"not json", True, "WireError: not JSON"),
    (b"[" * 100_000, True, "WireError: not JSON"),
    (json.dumps([1, 2]).encode(), False, "RequestError: a request must be"),
    (json.dumps({"cmd": "predict", "obs": "x"}).encode(), False, "RequestError: predict's obs"),
    (json.dumps(_predict(np.zeros(3))).encode(), False,
     r"must be 14 numbers \(shape \[14\], no batch axis\), got shape \[3\]"),
    (json.dumps({"cmd": "predict", "obs": {"joint_action": {"vector": _array(
        np.zeros(1, "<c16"))}}}).encode(), False, "RequestError: 'state' is not numbers"),
    (json.dumps({"cmd": "predict", "obs": {"joint_action": {"vector": {
        "__numpy_array__": True, "data": "AAAA", "dtype": "|O", "shape": [1]}}}}).encode(),
     True, "dtype object are refused"),
], ids=["not-json", "deep", "list", "obs", "state-shape", "state-complex", "object-array"])
def test_malformed_tcp_requests_get_an_error_reply_without_a_traceback(payload, closes,
                                                                         message):
    server = TcpPolicyServer(benchmark(), "noop")
    with served(server) as port, _client(port) as connection:
        connection.sendall(struct.pack(">I", len(payload)) + payload)
        reply = _read(connection)
        assert re.search(message, reply["error"]), reply
        _no_traceback(json.dumps(reply))
        if closes:  # out of step with the protocol: closed
            assert _read(connection) is None
        else:
            connection.sendall(_frame({"cmd": "reset", "obs": None}))
            assert "res" in _read(connection)


class _Exploding:
    uses = frozenset({"state"})

    def reset(self):
        pass

    def act(self, observation):
        raise RuntimeError("model crashed")


def exploding():
    return _Exploding()


def _ws_client(port: int):
    return connect(f"ws://127.0.0.1:{port}", compression=None, max_size=None,
                   open_timeout=WAIT)


@pytest.mark.parametrize("message, reply", [
    (b"\xc1garbage", "RequestError: not msgpack"),
    ("a text frame", "RequestError: a str message"),
    (packb([1, 2]), "RequestError: an observation must be a map"),
    (packb({"state": "abc"}), "RequestError: 'state' is not numbers"),
], ids=["garbage", "text", "list", "state"])
def test_malformed_websocket_messages_get_an_error_message_without_a_traceback(message, reply):
    server = PolicyServer(benchmark(), "noop")
    with served(server) as port:
        with _ws_client(port) as connection:
            unpackb(connection.recv(timeout=WAIT))  # the metadata
            connection.send(message)
            text = connection.recv(timeout=WAIT)
            assert isinstance(text, str) and text.startswith(reply), text
            _no_traceback(text)
            with pytest.raises(ConnectionClosed):
                connection.recv(timeout=WAIT)
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)  # still serving
        assert validate_actions(policy.act({"state": HOME, "instruction": "x"}))[0].shape == (
            50, 14)
        policy.close()


def test_a_failing_served_policy_sends_its_message_and_logs_its_traceback(caplog):
    server = PolicyServer(benchmark(), "tests.test_faults_servers:exploding")
    with served(server) as port:
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT, retries=0)
        with pytest.raises(PolicyServerError) as failure:
            policy.act({"state": HOME, "instruction": "x"})
        policy.close()
    assert str(failure.value) == (f"the policy server at ws://127.0.0.1:{port} failed: "
                                  "RuntimeError: model crashed")
    assert any(record.exc_info and "model crashed" in str(record.exc_info[1])
               for record in caplog.records)  # the traceback stays in the server's log


def test_the_websocket_server_refuses_an_oversize_request_and_goes_on_serving():
    server = PolicyServer(benchmark(), "noop", ServerLimits(max_message=5000))
    with served(server) as port:
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)
        images = {"cam_high": np.zeros((60, 80, 3), np.uint8)}  # 14 kB
        with pytest.raises(PolicyServerError, match="refused a message as over its size"):
            policy.act({"state": HOME, "instruction": "x", "images": images})
        assert policy.act({"state": HOME, "instruction": "x"}) is not None  # reconnects
        policy.close()


def test_an_idle_websocket_client_is_closed_and_does_not_block_another():
    server = PolicyServer(benchmark(), "noop", ServerLimits(idle_timeout=2.0))
    with served(server) as port:
        with _ws_client(port) as idle:
            idle.recv(timeout=WAIT)
            policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)
            policy.act({"state": HOME, "instruction": "x"})
            policy.close()
            with pytest.raises(TimeoutError):  # served while the idle one waits, still open
                idle.recv(timeout=0)
            with pytest.raises(ConnectionClosed):
                idle.recv(timeout=WAIT)


def _drop(connection: socket.socket, how: str) -> None:
    """Close `connection` at once, without a websocket close frame: "reset" (an RST, as a
    killed client's machine sends) or "close" (a FIN)."""
    if how == "reset":
        connection.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    connection.close()


def _handshaken(port: int) -> socket.socket:
    """A raw connection to the websocket server at `port`, its handshake complete."""
    connection = _client(port)
    connection.sendall(b"GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
                       b"Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
                       b"Sec-WebSocket-Version: 13\r\n\r\n")
    head = b""
    while b"\r\n\r\n" not in head:
        chunk = connection.recv(4096)
        assert chunk, head
        head += chunk
    assert head.startswith(b"HTTP/1.1 101 "), head
    return connection


def _at_most_a_line(records: list[logging.LogRecord]) -> None:
    """What a dropped client may leave in a server's log: no traceback, and at most one line
    besides websockets' own "connection open" and "connection closed" (INFO, for every
    client)."""
    lines = [r.getMessage() for r in records]
    assert not any(r.exc_info and r.exc_info[0] for r in records), lines
    assert len([r for r in records
                if r.levelno >= logging.WARNING or r.name == "robofollow.serve"]) <= 1, lines


class _LateWebsocketServer(PolicyServer):
    """`robofollow serve`'s websocket server, its first connection handled only once
    websockets has seen the client go (its reading thread has ended and closed the socket):
    a client dropping right after the handshake, without the race."""

    def __init__(self):
        super().__init__(benchmark(), "noop")
        self.first_handled = threading.Event()

    def handle(self, connection) -> None:
        if self.first_handled.is_set():
            return super().handle(connection)
        connection.recv_events_thread.join(WAIT)
        try:
            return super().handle(connection)
        finally:
            self.first_handled.set()


@pytest.mark.parametrize("how", ["reset", "close"])
def test_a_websocket_client_dropping_after_the_handshake_leaves_no_traceback(caplog, how):
    caplog.set_level(logging.INFO)
    server = _LateWebsocketServer()
    with served(server) as port:
        _drop(_handshaken(port), how)
        assert server.first_handled.wait(WAIT)
        policy = WebsocketPolicy(f"ws://127.0.0.1:{port}", timeout=WAIT)  # still serving
        assert validate_actions(policy.act({"state": HOME, "instruction": "x"}))[0].shape == (
            50, 14)
        policy.close()
    _at_most_a_line(caplog.records)  # (served() returns once every handler has ended)


@pytest.mark.parametrize("sent", [b"", b"\x00\x00", _frame(_predict())[:40], _frame(_predict()),
                                  b"GET /heal"],
                         ids=["nothing", "half-a-header", "mid-message", "a-request", "mid-http"])
@pytest.mark.parametrize("how", ["reset", "close"])
def test_a_tcp_client_dropping_at_once_or_mid_message_leaves_no_traceback(caplog, how, sent):
    caplog.set_level(logging.INFO)
    server = TcpPolicyServer(benchmark(), "noop", ServerLimits(idle_timeout=WAIT))
    with socket.create_server(("127.0.0.1", 0)) as listener:
        client = socket.create_connection(listener.getsockname(), timeout=WAIT)
        connection, peer = listener.accept()
        client.sendall(sent)
        _drop(client, how)
        server.handle(connection, peer)  # returns once the connection is over
    _at_most_a_line(caplog.records)
    with served(server) as port, _client(port) as connection:  # still serving
        connection.sendall(_frame({"cmd": "reset", "obs": None}))
        assert "res" in _read(connection)


# -- the default bind address ------------------------------------------------------------------

def _listening(port: int) -> list[str]:
    """Local addresses (hex, as /proc/net/tcp* gives them) listening on `port`."""
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        if not Path(table).is_file():
            continue
        for line in Path(table).read_text().splitlines()[1:]:
            fields = line.split()
            address, _, hex_port = fields[1].partition(":")
            if fields[3] == "0A" and int(hex_port, 16) == port:  # 0A: LISTEN
                found.append(address)
    return found


def _outside_address() -> str | None:
    """An address of this machine that is not loopback, if it has one."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        try:
            probe.connect(("192.0.2.1", 9))  # no packet is sent
            address = probe.getsockname()[0]
        except OSError:
            return None
    return None if address.startswith("127.") or address == "0.0.0.0" else address


def test_serve_defaults_to_listening_on_this_machine_only(capsys):
    assert parser().parse_args(["serve", "--policy", "noop"]).host == "127.0.0.1"
    with pytest.raises(SystemExit):
        main(["serve", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert "0.0.0.0 exposes the server" in help_text
    assert f"default: {MAX_MESSAGE_BYTES}" in help_text
    assert f"default: {IDLE_TIMEOUT_S:g})" in help_text and f"default: {MAX_CLIENTS})" in help_text


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/net/tcp").is_file(), reason="reads Linux's /proc/net/tcp")
def test_robofollow_serve_with_defaults_listens_on_loopback_only():
    with serve_process("--protocol", "tcp") as (process, port):
        with selectors.DefaultSelector() as selector:
            selector.register(process.stdout, selectors.EVENT_READ)
            assert selector.select(timeout=60), "serve did not start within 60 s"
        assert f"on tcp://127.0.0.1:{port}" in process.stdout.readline()
        assert _listening(port) == ["0100007F"]  # 127.0.0.1 only: not 0.0.0.0, not ::
        outside = _outside_address()
        if outside is not None:
            with pytest.raises(OSError):
                socket.create_connection((outside, port), timeout=2).close()
        with _client(port) as connection:  # and it is there on loopback
            connection.sendall(_frame({"cmd": "reset", "obs": None}))
            assert "res" in _read(connection)


# -- HTML reports escape what they show ----------------------------------------------------

def test_report_html_escapes_error_texts_policy_names_and_reasons(tmp_path):
    options = EvalOptions("<img src=x onerror=alert(2)>", ("scene2",), ("L0",), 1, "normal",
                          "none", "0" * 64)
    stages = [{"stage": "source", "name": "source", "weight": 1.0, "intent": 0.0,
               "execution": 0.0, "first_step": None, "reason": "<b>reason</b>"}]
    record = {"episode": "scene2/L0/<i>t</i>#r1", "scene": "scene2", "level": "L0",
              "task": "scene2/L0/<i>t</i>", "intent_score": 0.0, "execution_score": 0.0,
              "complete": False, "stages": stages,
              "executed_behaviour": {"match": "<u>other</u>", "description": ""},
              "error": "step 0: the policy raised PolicyServerError: the policy server failed: "
                       "<script>alert(1)</script>", "video": "javascript:alert(3)"}
    run = tmp_path / "run"
    run.mkdir()
    (run / "run.json").write_text(json.dumps(options.to_json()))
    (run / "episodes.jsonl").write_text(json.dumps(record) + "\n")
    _, html = write_report(run)
    page = html.read_text()
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in page
    for shown in (page, (run / "tasks.html").read_text()):
        for raw in ("<script>", "<img src=x", "<b>reason", "<i>t", "<u>other", "javascript:"):
            assert raw not in shown, raw


def test_every_html_template_autoescapes_and_none_marks_a_value_safe():
    from robofollow.eval.reports.pages import PAGES

    package = Path(__file__).parents[1] / "robofollow"
    html = [path for path in package.rglob("*.j2") if ".html" in path.name]
    assert html  # report.html.j2 at least
    for path in html:
        assert path.parent.name == "templates" and path.parent.parent.name == "reports", path
        assert PAGES.autoescape(path.name) is True
        assert not re.search(r"\|\s*safe|Markup|autoescape\s+false", path.read_text()), path
    for module in (package / "eval" / "reports").glob("*.py"):
        assert "Markup" not in module.read_text(), module


# -- privileged observations ---------------------------------------------------------------

def _privileged_ws(seen: list):
    """Declares it uses privileged observations and holds the state; records every message."""
    def handler(connection):
        connection.send(packb({"robofollow": {"uses": ["state", "privileged"]}}))
        for data in connection:
            message = unpackb(data)
            seen.append(message)
            reply = ({"reset": True} if message.get("reset")
                     else {"actions": np.repeat(message["state"][None], 50, axis=0)})
            connection.send(packb(reply))
    return handler


FAKE = SimpleNamespace(scene=SimpleNamespace(id="scene2"), sim=SimpleNamespace(layout="default"),
                       seed=7)


def test_privileged_observations_are_sent_only_when_allowed():
    seen: list = []
    with ws_server(_privileged_ws(seen)) as uri:
        with pytest.raises(PrivilegedRefusedError, match="--allow-privileged"):
            load_policy(uri)
        allowed = load_policy(uri + "?privileged=1")
        assert "privileged" in allowed.uses
        allowed.act({"state": HOME, "instruction": "x", "privileged": FAKE})
        allowed.close()
    assert len(seen) == 1 and seen[0]["privileged"] == {"scene": "scene2",
                                                        "layout": "default", "seed": 7}
    openpi: list = []

    def plain(connection):  # an openpi server: declares nothing
        connection.send(packb({}))
        for data in connection:
            openpi.append(unpackb(data))
            connection.send(packb({"actions": np.zeros((1, 14))}))

    with ws_server(plain) as uri:
        policy = load_policy(uri)
        policy.act({"state": HOME, "instruction": "x", "privileged": FAKE})
        policy.close()
    assert len(openpi) == 1 and "privileged" not in openpi[0]  # not even by mistake
    log: list = []

    def upstream(connection):  # an upstream server: declares nothing
        while (request := _read(connection)) is not None:
            log.append(request)
            connection.sendall(_frame({"res": _array(np.zeros((1, 14)))}))

    with raw_server(upstream) as (port, _):
        policy = TcpPolicy("127.0.0.1", port, timeout=WAIT)
        policy.act({"state": HOME, "instruction": "x", "privileged": FAKE})
        policy.close()
    assert "privileged" not in log[-1]["obs"]  # not even when handed one by mistake


def test_a_tcp_server_asking_for_privileged_observations_is_refused_without_the_flag():
    server = TcpPolicyServer(benchmark(), "expert")
    with served(server) as port:
        with pytest.raises(PrivilegedRefusedError, match="--allow-privileged"):
            load_policy(f"tcp://127.0.0.1:{port}").reset()
        allowed = load_policy(f"tcp://127.0.0.1:{port}?privileged=1")
        allowed.reset()
        assert allowed.uses == {"instruction", "privileged"}
        allowed.close()
        with _client(port) as connection:  # a client that sends none: told why
            connection.sendall(_frame({"cmd": "reset", "obs": None}))
            _read(connection)
            connection.sendall(_frame(_predict()))
            reply = _read(connection)
    assert "reads privileged observations" in reply["error"]
    assert "--allow-privileged" in reply["error"]


def test_eval_sends_privileged_observations_only_with_the_flag_and_records_it(tmp_path, capsys):
    seen: list = []
    common = ["--specs", str(builtin_specs()), "--tasks", "scene2/L0/pickup_left_cube",
              "--rounds", "1", "--workers", "1", "--quiet"]
    with ws_server(_privileged_ws(seen)) as uri:
        assert main(["eval", "--policy", uri, "--out", str(tmp_path / "no"), *common]) == 1
        assert "--allow-privileged" in capsys.readouterr().err and seen == []
        assert main(["eval", "--policy", uri, "--allow-privileged", "--out",
                     str(tmp_path / "yes"), *common]) == 0
    run = json.loads((tmp_path / "yes" / "run.json").read_text())
    assert run["policy"] == uri + "?privileged=1"
    observations = [m for m in seen if "state" in m]
    assert len(observations) == 10 and all(
        m["privileged"] == {"scene": "scene2", "layout": episode(EPISODE).layout,
                            "seed": episode(EPISODE).seed} for m in observations)
    assert main(["eval", "--policy", "noop", "--allow-privileged", "--out",
                 str(tmp_path / "local"), *common]) == 2
    assert "for policy servers" in capsys.readouterr().err


def test_bad_server_settings_are_load_errors():
    for spec in ("ws://h:1?max_message=0", "tcp://h:1?privileged=2", "tcp://h:1?retries=-1",
                 "ws://h:1?timeout=0", "tcp://h:1?max_message=big"):
        with pytest.raises(PolicyLoadError, match=re.escape(spec)):
            load_policy(spec)
