"""Compile-time analysis of task sets: scene entropy, the split audit (leakage, repertoire,
ambiguity, feasibility), the audit report put together from its scenes' parts, and the audit
of listed tests and task lists."""
