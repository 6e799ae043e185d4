"""Compile-time analysis of task sets: scene entropy, the split audit (leakage, repertoire,
ambiguity, feasibility) and the audit of listed tests and task lists."""
