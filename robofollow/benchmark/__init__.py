"""Compile the benchmark: specs -> checked training tasks -> L0-L3 splits -> audit
(`pipeline`, scene by scene), the compiled benchmark its scenes' parts make (`compiled`); what
an episode is (`episode`) and a build's episodes (`rounds`); the build's files as text
(`render`), its folder (`output`) and its summary for people (`summary`); the best blind guess
(`guessing`) and its warnings (`guess_warnings`)."""
