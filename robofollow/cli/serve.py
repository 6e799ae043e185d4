"""`robofollow serve`: a Python policy behind a websocket or TCP server."""

from __future__ import annotations

import argparse
import ipaddress
import sys

from robofollow.cli.common import benchmark_of, benchmark_options, positive, seconds
from robofollow.errors import RoboFollowError, UsageError
from robofollow.eval.protocols.limits import (
    DEFAULT_HOST,
    IDLE_TIMEOUT_S,
    MAX_CLIENTS,
    MAX_MESSAGE_BYTES,
)

MAX_PORT = 65535
LOCAL_NAME = "localhost"  # the one host name taken for this machine; others may resolve anywhere


def add_serve(commands) -> None:
    p = commands.add_parser(
        "serve", help="serve a Python policy over openpi's websocket or upstream's TCP protocol",
        description="Expose a policy (a reference policy or module:factory) as a server: "
                    "websocket speaking openpi's protocol (msgpack-numpy, metadata on connect, "
                    "replies {'actions': [H, 14]}), for `robofollow eval --policy ws://HOST:PORT`"
                    " or any openpi client; or tcp speaking upstream RoboFollow's protocol "
                    "(length-prefixed JSON; reset / set_instruction / predict), for "
                    "`robofollow eval --policy tcp://HOST:PORT` or upstream's evaluator.")
    p.add_argument("--protocol", choices=("websocket", "tcp"), default="websocket",
                   help="wire protocol (default: websocket)")
    p.add_argument("--policy", required=True, help="expert, blind, noop, random, "
                   "baseline:NAME, a checkpoint folder, or module:factory")
    p.add_argument("--host", default=DEFAULT_HOST,
                   help=f"address to listen on (default: {DEFAULT_HOST}, this machine only); "
                        f"one that is not loopback (127.0.0.0/8, ::1, {LOCAL_NAME}) is refused "
                        "without --allow-remote")
    p.add_argument("--allow-remote", action="store_true",
                   help="let --host be an address that is not loopback: --host 0.0.0.0 "
                        "exposes the server to every network this machine is on, without "
                        "authentication (only on a network you trust)")
    p.add_argument("--port", type=port_number, default=8000,
                   help=f"port, 0..{MAX_PORT} (default: 8000; 0: any free port, printed once "
                        "listening)")
    p.add_argument("--max-message", type=positive, metavar="BYTES",
                   help="refuse requests larger than this, closing the connection (default: "
                        f"{MAX_MESSAGE_BYTES}, {MAX_MESSAGE_BYTES // 2 ** 20} MiB; three 320x240 "
                        "images take about 1 MiB)")
    p.add_argument("--idle-timeout", type=seconds, metavar="S",
                   help="close a connection that sends nothing for S seconds "
                        f"(default: {IDLE_TIMEOUT_S:g})")
    p.add_argument("--max-clients", type=positive, metavar="N",
                   help="connections served at once, each with its own instance of the "
                        f"policy; more are refused (default: {MAX_CLIENTS})")
    benchmark_options(p)
    p.set_defaults(handler=cmd_serve)


def port_number(text: str) -> int:
    """A TCP port: a whole number from 0 to MAX_PORT."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 0 <= value <= MAX_PORT:
        raise argparse.ArgumentTypeError(f"must be from 0 to {MAX_PORT}, got {value}")
    return value


def is_local(host: str) -> bool:
    """Whether listening on `host` serves this machine only: a loopback address or
    localhost ('' binds every interface)."""
    if host.lower() == LOCAL_NAME:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:  # a host name, or ''
        return False


def check_host(host: str, allow_remote: bool) -> None:
    """Refuse (UsageError) a host that is not local unless `allow_remote`; with it, warn on
    stderr that the server is exposed."""
    if is_local(host):
        return
    if not allow_remote:
        raise UsageError(f"--host {host!r} is not a loopback address (127.0.0.0/8, ::1, "
                         f"{LOCAL_NAME}): the server has no authentication; add --allow-remote "
                         "to expose it to the network on purpose")
    print(f"warning: --host {host!r} exposes the server to the network without "
          "authentication: anyone who reaches it can drive the policy", file=sys.stderr,
          flush=True)


def url_host(host: str) -> str:
    """`host` as a URL writes it: an IPv6 address in brackets."""
    return f"[{host}]" if ":" in host else host


def cmd_serve(args) -> int:
    check_host(args.host, args.allow_remote)  # before anything is loaded
    import logging

    from robofollow.eval.serving.serving import ServerLimits
    from robofollow.eval.serving.tcp_server import TcpPolicyServer
    from robofollow.eval.serving.websocket_server import PolicyServer

    server_class, scheme = ((TcpPolicyServer, "tcp") if args.protocol == "tcp"
                            else (PolicyServer, "ws"))
    limits = ServerLimits(args.max_message, args.idle_timeout, args.max_clients)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    server = server_class(benchmark_of(args), args.policy, limits)

    def listening(listener) -> None:  # only now can a client connect
        host, port = listener.getsockname()[:2]  # as bound: the port 0 chose, '' as 0.0.0.0
        address = f"{url_host(host)}:{port}"
        print(f"serving {args.policy} on {scheme}://{address} (Ctrl-C stops; "
              f"health check: http://{address}/healthz)", flush=True)
        if "privileged" in server.pool.uses:
            print(f"note: {args.policy} is a reference policy reading privileged observations: "
                  "only `robofollow eval --allow-privileged` clients can drive it; other "
                  "clients (openpi's) get an error reply saying so", file=sys.stderr, flush=True)

    try:
        server.serve_forever(args.host, args.port, ready=listening)
    except KeyboardInterrupt:
        pass  # Ctrl-C is how a server is stopped
    except OSError as error:  # e.g. the port is taken, or no such address here
        raise RoboFollowError(f"cannot listen on {url_host(args.host)}:{args.port}: "
                              f"{error}") from None
    return 0
