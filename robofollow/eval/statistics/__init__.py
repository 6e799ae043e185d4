"""The statistics a report or a paper cites: numbers in, numbers out; no file is read here.

Per-cell tables and Wilson intervals (metrics.py), task-cluster intervals, paired and unpaired
tests and Holm's adjustment (intervals.py), paired comparisons of two runs' episodes
(paired.py), level drops (drops.py), power plans (power.py) and the sequential test
(sequential.py). Imports nothing of eval.
"""
