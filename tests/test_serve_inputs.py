"""`robofollow serve` facing bad input: a host that is not this machine's is refused unless
--allow-remote says so, --port is a port (0 for any free one), observations holding NaN,
infinite numbers or numbers beyond MAX_OBSERVATION_MAGNITUDE get the protocol's error reply over
both protocols, and so do a served policy's actions that are not finite [T, 14] numbers (instead
of the actions), the server going on."""

from __future__ import annotations

import re
import selectors

import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from robofollow.cli import main, parser
from robofollow.cli.serve import check_host
from robofollow.eval.protocols.limits import MAX_OBSERVATION_MAGNITUDE
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


MUST = f"must be finite numbers of magnitude at most {MAX_OBSERVATION_MAGNITUDE:g}"
NON_FINITE = [  # (state, objects, the error's start)
    (_with(np.nan, 3, HOME), OBJECTS, f"'state' {MUST}; got nan at [3]"),
    (_with(np.inf, 0, HOME), OBJECTS, f"'state' {MUST}; got inf at [0]"),
    (_with(-np.inf, 13, HOME, np.float64), OBJECTS, f"'state' {MUST}; got -inf at [13]"),
    (_with(1e39, 5, HOME, np.float64), OBJECTS, f"'state' {MUST}; got inf at [5]"),
    (HOME, _with(np.nan, (2, 4), OBJECTS), f"'objects' {MUST}; got nan at [2, 4]"),
    (HOME, _with(-np.inf, (0, 0), OBJECTS), f"'objects' {MUST}; got -inf at [0, 0]"),
    (_with(3e38, 6, HOME), OBJECTS, f"'state' {MUST}; got 3e+38 at [6]"),
    (_with(-2e6, 1, HOME, np.float64), OBJECTS, f"'state' {MUST}; got -2e+06 at [1]"),
    (_with(2 ** 62, 2, HOME, np.int64), OBJECTS, f"'state' {MUST}; got 4.61169e+18 at [2]"),
    (HOME, _with(1e20, (1, 12), OBJECTS), f"'objects' {MUST}; got 1e+20 at [1, 12]"),
]
NON_FINITE_IDS = ["state-nan", "state-inf", "state-minus-inf-f64", "state-beyond-float32",
                  "objects-nan", "objects-minus-inf", "state-3e38", "state-minus-2e6-f64",
                  "state-huge-int", "objects-1e20"]


def _ws_act(port: int, state: np.ndarray, objects: np.ndarray, prompt: str = "x"):
    """The reply to one observation on a new websocket connection: actions, or the error text
    (the connection then closed)."""
    with connect(f"ws://127.0.0.1:{port}", compression=None, open_timeout=WAIT) as ws:
        unpackb(ws.recv(timeout=WAIT))  # the metadata
        ws.send(packb({"state": state, "prompt": prompt, "objects": objects}))
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


def _tcp_predict(connection, state, objects, instruction: str = "x") -> dict:
    """The reply to a predict request; `state` a list travels as JSON numbers (Python's json
    writes NaN, Infinity and -Infinity literals)."""
    vector = state if isinstance(state, list) else _array(state)
    connection.sendall(_frame({"cmd": "predict", "obs": {
        "joint_action": {"vector": vector}, "instruction": instruction,
        "objects": _array(objects)}}))
    return _read(connection)


@pytest.mark.parametrize("state, objects, message", NON_FINITE + [
    (_with(np.nan, 1, HOME).tolist(), OBJECTS, f"'state' {MUST}; got nan at [1]"),
    (_with(np.inf, 2, HOME).tolist(), OBJECTS, f"'state' {MUST}; got inf at [2]"),
    ([-1e400] * 14, OBJECTS, f"'state' {MUST}; got -inf at [0]"),
    ([1e20] * 14, OBJECTS, f"'state' {MUST}; got 1e+20 at [0]"),
], ids=[*NON_FINITE_IDS, "json-NaN", "json-Infinity", "json-minus-Infinity", "json-1e20"])
def test_a_non_finite_tcp_observation_gets_an_error_reply_and_the_connection_goes_on(
        state, objects, message):
    with served(TcpPolicyServer(benchmark(), "tests.test_serve_inputs:echo")) as port, \
            _client(port) as connection:
        reply = _tcp_predict(connection, state, objects)
        assert reply.get("error", "").startswith(f"RequestError: {message}"), reply
        good = _tcp_predict(connection, HOME, OBJECTS)
    assert good["res"]["shape"] == [1, 14]


# -- actions a served policy returns -----------------------------------------------------------

ROW = np.zeros((1, 14))
REFUSED = "BadActionError: the policy returned actions the protocol cannot carry: "
NOT_FINITE, SHAPED, NUMBERS = ("action {} has a non-finite value at {}",
                               "actions must be [T, 14] with T >= 1, got shape {}",
                               "actions are not numbers: got {} (expected real joint targets)")
BAD_ACTIONS = {  # instruction: (what the policy returns, what the error reply says is wrong)
    "nan": (_with(np.nan, (1, 3), np.zeros((2, 14))), NOT_FINITE.format(1, robot.JOINT_NAMES[3])),
    "minus-inf": (_with(-np.inf, (0, 13), ROW), NOT_FINITE.format(0, robot.JOINT_NAMES[13])),
    "beyond-float32": (_with(1e39, (0, 0), ROW, np.float64),
                       NOT_FINITE.format(0, robot.JOINT_NAMES[0])),
    "shape": (np.zeros((2, 7)), SHAPED.format([2, 7])),
    "batch-axis": (np.zeros((1, 2, 14)), SHAPED.format([1, 2, 14])),
    "strings": ([["0.5"] * 14], NUMBERS.format("strings")),
    "none": (None, NUMBERS.format("objects")),
}


class Misbehaving(Echo):
    """Returns the bad chunk its instruction names (BAD_ACTIONS), else its state."""

    def act(self, observation: dict):
        bad = BAD_ACTIONS.get(observation["instruction"])
        return super().act(observation) if bad is None else bad[0]


def misbehaving():
    return Misbehaving()


class Amplifying(Echo):
    """Acts its state times 1e35, in float64: finite, yet beyond float32's range where the
    state is over 3.4e3."""

    def act(self, observation: dict) -> np.ndarray:
        return super().act(observation).astype(np.float64) * 1e35


def amplifying():
    return Amplifying()


def _served_replies(policy: str, state: np.ndarray, instruction: str) -> list:
    """The replies to one observation over each protocol (the websocket's error text or
    actions, TCP's error message), each server checked to go on serving: a request of HOME
    after it gets actions (over TCP on the same connection)."""
    with served(PolicyServer(benchmark(), policy)) as port:
        replies = [_ws_act(port, state, OBJECTS, instruction)]
        assert _ws_act(port, HOME, OBJECTS).shape == (1, 14)
    with served(TcpPolicyServer(benchmark(), policy)) as port, _client(port) as connection:
        replies.append(_tcp_predict(connection, state, OBJECTS, instruction).get("error"))
        assert _tcp_predict(connection, HOME, OBJECTS)["res"]["shape"] == [1, 14]
    return replies


@pytest.mark.parametrize("instruction", list(BAD_ACTIONS))
def test_a_served_policys_bad_actions_get_an_error_reply_instead(instruction):
    expected = REFUSED + BAD_ACTIONS[instruction][1]
    for reply in _served_replies("tests.test_serve_inputs:misbehaving", HOME, instruction):
        assert isinstance(reply, str) and reply == expected, reply


def test_an_accepted_state_a_policy_turns_infinite_gets_an_error_reply_instead():
    state = _with(1e5, 4, HOME)  # within MAX_OBSERVATION_MAGNITUDE: it reaches the policy
    expected = REFUSED + NOT_FINITE.format(0, robot.JOINT_NAMES[4])
    for reply in _served_replies("tests.test_serve_inputs:amplifying", state, "x"):
        assert isinstance(reply, str) and reply == expected, reply
