"""Compile the benchmark: specs -> checked training tasks -> L0-L3 splits -> audit
(`pipeline`); what an episode is (`episode`) and a build's episodes (`rounds`); the build's
folder (`output`) and its summary for people (`summary`)."""
