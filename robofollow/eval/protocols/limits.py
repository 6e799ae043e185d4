"""The harness's limits on a policy and the defaults of a policy server, with no imports, so
that the command line's help quotes them without loading the simulation."""

from __future__ import annotations

CALL_TIMEOUT_S = 60.0  # a policy server client's wait for a reply before it retries

# The largest message either end of either protocol accepts, in bytes: an observation with
# three 320x240 camera images is under 1 MiB (msgpack) or 1.3 MiB (JSON with base64), a reply
# a few KiB. Raised per server with `robofollow serve --max-message BYTES`, per client with
# `--policy URL?max_message=BYTES`.
MAX_MESSAGE_BYTES = 16 * 2 ** 20

DEFAULT_HOST = "127.0.0.1"  # this machine only; 0.0.0.0 exposes a server to the network
IDLE_TIMEOUT_S = 300.0  # a connection that sends nothing for this long is closed
MAX_CLIENTS = 8  # connections served at once, each with its own policy instance

# The largest magnitude a number in a served observation's 'state' or 'objects' may have; a
# server refuses one beyond it, as it refuses NaN. No genuine observation comes near: joint
# angles lie within the joint limits (|q| <= pi rad), grippers, colours and one-hots from 0 to
# 1, yaw sines and cosines, sizes and positions in metres on a table (expert and random
# episodes peak at 1.8). A number past it is a client's bug (wrong units, garbage) that a
# policy could turn into infinite actions.
MAX_OBSERVATION_MAGNITUDE = 1e6
