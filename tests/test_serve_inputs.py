"""`robofollow serve` facing bad input: a host that is not this machine's is refused unless
--allow-remote says so, --port is a port (0 for any free one), and observations holding NaN or
infinite numbers get the protocol's error reply over both protocols, the server going on."""

from __future__ import annotations

import re
import selectors

import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from robofollow.cli import main, parser
from robofollow.cli.serve import check_host
from robofollow.eval.protocols.wire import packb, unpackb
from robofollow.eval.serving.tcp_server import TcpPolicyServer
from robofollow.eval.serving.websocket_server import PolicyServer
from robofollow.sim import robot
from robofollow.sim.objects import SHAPE
from tests.server_helpers import WAIT, _array, _client, _frame, _read, served
from tests.sim_helpers import benchmark, serve_process

HOME = robot.home_state().astype(np.float32)
OBJECTS = np.zeros(SHAPE, np.float32)
ERROR_LINE = re.compile(r"^robofollow serve: error: argument --port: ")


def _serve(capsys, *options: str) -> tuple[int, list[str]]:
    """`robofollow serve --policy noop` with `options` and specs that do not exist (reaching
    them fails: what is refused before is refused before loading): exit status, stderr lines."""
    try:
        code = main(["serve", "--policy", "noop", "--specs", "/no/such/specs", *options])
    except SystemExit as exit_:  # argparse's refusal
        code = exit_.code
    return code, capsys.readouterr().err.splitlines()


# -- the host ----------------------------------------------------------------------------------

@pytest.mark.parametrize("host", ["", "0.0.0.0", "::", "192.168.1.10", "example.com",
                                  "localhost.example.com"])
def test_a_host_that_is_not_loopback_is_refused_before_anything_is_loaded(capsys, host):
    code, err = _serve(capsys, "--host", host)
    assert code == 2 and len(err) == 1, err
    assert err[0].startswith(f"error: --host {host!r} is not a loopback address")
    assert "--allow-remote" in err[0]


@pytest.mark.parametrize("host", ["127.0.0.1", "127.8.9.10", "::1", "localhost", "LOCALHOST"])
def test_a_loopback_host_is_served_without_a_word(capsys, host):
    check_host(host, allow_remote=False)
    assert capsys.readouterr().err == ""


def test_allow_remote_lets_another_host_through_with_a_warning_and_says_so_in_help(capsys):
    check_host("0.0.0.0", allow_remote=True)
    assert "exposes the server to the network without authentication" in (
        capsys.readouterr().err)
    code, err = _serve(capsys, "--host", "", "--allow-remote")
    assert code == 1 and err[0].startswith("warning: --host '' exposes the server")
    assert "/no/such/specs" in err[1]  # past the host check, to loading the specs
    with pytest.raises(SystemExit):
        main(["serve", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    assert ("--allow-remote let --host be an address that is not loopback: --host 0.0.0.0 "
            "exposes the server to every network") in help_text


# -- the port ----------------------------------------------------------------------------------

@pytest.mark.parametrize("port, message", [
    ("70000", "must be from 0 to 65535, got 70000"),
    ("65536", "must be from 0 to 65535, got 65536"),
    ("-1", "must be from 0 to 65535, got -1"),
    ("x", "expected a port number, got 'x'"),
])
def test_a_port_out_of_range_is_argparses_one_line_error(capsys, port, message):
    code, err = _serve(capsys, f"--port={port}")
    assert code == 2 and len(err) == 1, err  # one line, pointing to --help
    assert ERROR_LINE.match(err[0]) and f"{message} (see robofollow serve --help)" in err[0]
    assert not any("Traceback" in line for line in err)


def test_port_0_and_65535_are_ports():
    assert [parser().parse_args(["serve", "--policy", "noop", "--port", port]).port
            for port in ("0", "65535")] == [0, 65535]


@pytest.mark.slow
def test_serving_on_port_0_prints_the_port_chosen():
    with serve_process("--protocol", "tcp", "--port", "0") as (process, _):
        with selectors.DefaultSelector() as selector:
            selector.register(process.stdout, selectors.EVENT_READ)
            assert selector.select(timeout=60), "serve did not start within 60 s"
        line = process.stdout.readline()
        port = int(re.search(r"on tcp://127\.0\.0\.1:(\d+) ", line)[1])
        assert port != 0 and f"http://127.0.0.1:{port}/healthz" in line
        with _client(port) as connection:
            connection.sendall(_frame({"cmd": "reset", "obs": None}))
            assert "res" in _read(connection)


# -- non-finite observations -------------------------------------------------------------------

class Echo:
    """Reads the state and the objects observation; acts its state."""

    uses = frozenset({"state", "instruction", "objects"})

    def reset(self) -> None:
        pass

    def act(self, observation: dict) -> np.ndarray:
        return observation["state"][None]


def echo():
    return Echo()


def _with(value: float, at, like: np.ndarray, dtype=np.float32) -> np.ndarray:
    array = like.astype(dtype)
    array[at] = value
    return array


NON_FINITE = [  # (state, objects, the error's start)
    (_with(np.nan, 3, HOME), OBJECTS, "'state' must be finite numbers; got nan at [3]"),
    (_with(np.inf, 0, HOME), OBJECTS, "'state' must be finite numbers; got inf at [0]"),
    (_with(-np.inf, 13, HOME, np.float64), OBJECTS,
     "'state' must be finite numbers; got -inf at [13]"),
    (_with(1e39, 5, HOME, np.float64), OBJECTS, "'state' must be finite numbers; got inf at [5]"),
    (HOME, _with(np.nan, (2, 4), OBJECTS), "'objects' must be finite numbers; got nan at [2, 4]"),
    (HOME, _with(-np.inf, (0, 0), OBJECTS),
     "'objects' must be finite numbers; got -inf at [0, 0]"),
]
NON_FINITE_IDS = ["state-nan", "state-inf", "state-minus-inf-f64", "state-beyond-float32",
                  "objects-nan", "objects-minus-inf"]


def _ws_act(port: int, state: np.ndarray, objects: np.ndarray):
    """The reply to one observation on a new websocket connection: actions, or the error text
    (the connection then closed)."""
    with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
        unpackb(ws.recv(timeout=WAIT))  # the metadata
        ws.send(packb({"state": state, "prompt": "x", "objects": objects}))
        reply = ws.recv(timeout=WAIT)
        if isinstance(reply, str):
            with pytest.raises(ConnectionClosed):
                ws.recv(timeout=WAIT)
            return reply
        return unpackb(reply)["actions"]


@pytest.mark.parametrize("state, objects, message", NON_FINITE, ids=NON_FINITE_IDS)
def test_a_non_finite_websocket_observation_gets_an_error_reply(state, objects, message):
    with served(PolicyServer(benchmark(), "tests.test_serve_inputs:echo")) as port:
        reply = _ws_act(port, state, objects)
        assert isinstance(reply, str) and reply.startswith(f"RequestError: {message}"), reply
        np.testing.assert_array_equal(_ws_act(port, HOME, OBJECTS), HOME[None])  # serving


def _tcp_predict(connection, state, objects) -> dict:
    """The reply to a predict request; `state` a list travels as JSON numbers (Python's json
    writes NaN, Infinity and -Infinity literals)."""
    vector = state if isinstance(state, list) else _array(state)
    connection.sendall(_frame({"cmd": "predict", "obs": {
        "joint_action": {"vector": vector}, "instruction": "x", "objects": _array(objects)}}))
    return _read(connection)


@pytest.mark.parametrize("state, objects, message", NON_FINITE + [
    (_with(np.nan, 1, HOME).tolist(), OBJECTS, "'state' must be finite numbers; got nan at [1]"),
    (_with(np.inf, 2, HOME).tolist(), OBJECTS, "'state' must be finite numbers; got inf at [2]"),
    ([-1e400] * 14, OBJECTS, "'state' must be finite numbers; got -inf at [0]"),
], ids=[*NON_FINITE_IDS, "json-NaN", "json-Infinity", "json-minus-Infinity"])
def test_a_non_finite_tcp_observation_gets_an_error_reply_and_the_connection_goes_on(
        state, objects, message):
    with served(TcpPolicyServer(benchmark(), "tests.test_serve_inputs:echo")) as port, \
            _client(port) as connection:
        reply = _tcp_predict(connection, state, objects)
        assert reply.get("error", "").startswith(f"RequestError: {message}"), reply
        good = _tcp_predict(connection, HOME, OBJECTS)
    assert good["res"]["shape"] == [1, 14]
