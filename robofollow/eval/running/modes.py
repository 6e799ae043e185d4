"""The choices an evaluation run takes, with no imports, so that the command line offers them
without loading the harness."""

INSTRUCTION_MODES = ("normal", "empty", "shuffled")  # the episode's, none, or another task's
VIDEO_MODES = ("none", "failures", "all")  # which episodes get an mp4
EXPORTS = {"csv": "table1.csv", "latex": "table1.tex"}  # report --export: Table 1 files
POWER_GROUPS = ("level", "cell")  # compare --power --by: plan per level or per scene x level
