"""The split generator: training tasks checked against their layouts (training.py), novel
wordings (wordings.py, wording_rules.py), the rules every test task obeys (task_rules.py), the
L0-L3 generator itself (generator.py), the records it makes (tasks.py) and what the split rules
did (split_report.py).

The top room of the compiler: it may import every other one.
"""
