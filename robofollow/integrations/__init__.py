"""Adapters that let other evaluation harnesses run RoboFollow episodes with its own scoring
(vla_eval: allenai's vla-evaluation-harness)."""
