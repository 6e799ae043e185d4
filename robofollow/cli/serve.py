"""`robofollow serve`: a Python policy behind a websocket or TCP server."""

from __future__ import annotations

import sys

from robofollow.cli.common import positive, seconds, specs_of, specs_option
from robofollow.errors import RoboFollowError
from robofollow.eval.limits import DEFAULT_HOST, IDLE_TIMEOUT_S, MAX_CLIENTS, MAX_MESSAGE_BYTES


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
                   help=f"address to listen on (default: {DEFAULT_HOST}, this machine only; "
                        "--host 0.0.0.0 exposes the server to every network this machine is "
                        "on, without authentication: only on a network you trust)")
    p.add_argument("--port", type=positive, default=8000, help="port (default: 8000)")
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
    specs_option(p)
    p.set_defaults(handler=cmd_serve)


def cmd_serve(args) -> int:
    import logging

    from robofollow.compiled_cache import load
    from robofollow.eval.serving import ServerLimits
    from robofollow.eval.tcp_server import TcpPolicyServer
    from robofollow.eval.websocket_server import PolicyServer

    server_class, scheme = ((TcpPolicyServer, "tcp") if args.protocol == "tcp"
                            else (PolicyServer, "ws"))
    limits = ServerLimits(args.max_message, args.idle_timeout, args.max_clients)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    server = server_class(load(specs_of(args)), args.policy, limits)

    def listening(_) -> None:  # only now can a client connect
        print(f"serving {args.policy} on {scheme}://{args.host}:{args.port} (Ctrl-C stops; "
              f"health check: http://{args.host}:{args.port}/healthz)", flush=True)
        if "privileged" in server.pool.uses:
            print(f"note: {args.policy} is a reference policy reading privileged observations: "
                  "only `robofollow eval --allow-privileged` clients can drive it; other "
                  "clients (openpi's) get an error reply saying so", file=sys.stderr, flush=True)

    try:
        server.serve_forever(args.host, args.port, ready=listening)
    except KeyboardInterrupt:
        pass  # Ctrl-C is how a server is stopped
    except OSError as error:  # e.g. the port is taken, or no such address here
        raise RoboFollowError(f"cannot listen on {args.host}:{args.port}: {error}") from None
    return 0
