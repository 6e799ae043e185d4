"""Running a policy over the benchmark: episodes in MuJoCo under a deadline, scored by the
oracle; run folders written atomically, resumed, sharded and merged; recorded runs read back
(saved_run.py, scores.py) and reproduced. Imports policies, statistics and protocols.
"""
