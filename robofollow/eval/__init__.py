"""Evaluating policies over the benchmark: the policy interface, reference policies, episodes."""
