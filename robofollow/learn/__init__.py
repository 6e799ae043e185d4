"""Learned baselines: dataset reader, instruction tokens, the network, training, checkpoints
and checkpoints as policies."""
