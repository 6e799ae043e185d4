"""What a policy client and a policy server say to each other: msgpack arrays on the wire
(wire.py), upstream's TCP framing (tcp_protocol.py), and the limits both ends keep
(limits.py). Imports nothing of eval: the lowest room.
"""
