"""Faults of `robofollow eval` that a probe found, each kept fixed: a policy whose process
dies, exits or cannot be built; outputs that cannot be written (a folder that cannot be made or
written, a path that is a file, a disk that fills mid-run); a corrupt line in
RUN/episodes.jsonl; two runs on one folder at once. Every check runs the command with a time
limit (a hang fails the test), and asks for an exit status and a message, no traceback, every
episode recorded exactly once and every failure with its reason."""

from __future__ import annotations

import errno
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from robofollow.resources import builtin_specs

ROOT = Path(__file__).resolve().parent.parent
SPECS = builtin_specs() / "scene1.rf"  # one scene compiles in about a second
TASKS = {  # scene1/L0 task -> what the faulty policy does on its instruction
    "scene1/L0/pickup_yellow_block_3": "os._exit(1)",  # "... in front of the red cylinder."
    "scene1/L0/pickup_yellow_block_2": "SystemExit(0)",  # "... left of the green ball."
    "scene1/L0/pickup_yellow_block_1_left": "RuntimeError",  # "Use your left arm ... right"
    "scene1/L0/pickup_yellow_block_1_right": None,  # holds still: a whole, ordinary episode
}
EXPECTED_ERRORS = {
    "scene1/L0/pickup_yellow_block_3": "the policy process exited with status 1 during the "
                                       "episode",
    "scene1/L0/pickup_yellow_block_2": "step 0: the policy raised SystemExit(0)",
    "scene1/L0/pickup_yellow_block_1_left": "step 0: the policy raised RuntimeError: boom",
    "scene1/L0/pickup_yellow_block_1_right": None,
}
LIMIT = 60  # seconds any one command may take before it counts as hung
GATE = "ROBOFOLLOW_TEST_GATE"


# -- policies (loaded by the commands as tests.test_faults_eval:FACTORY) ----------------------

class Faulty:
    """Fails on some instructions (os._exit, SystemExit, an exception), holds on the rest."""
    uses = frozenset({"state"})

    def __init__(self, exits: bool = True):
        self.exits = exits

    def reset(self):
        pass

    def act(self, observation):
        text = observation["instruction"]
        if "in front of the red cylinder" in text and self.exits:
            os._exit(1)
        if "left of the green ball" in text:
            if os.environ.get(GATE) == "interrupt":  # (as Ctrl-C would)
                raise KeyboardInterrupt
            raise SystemExit(0)
        if text.startswith("Use your left arm to pick up the block to the right"):
            raise RuntimeError("boom")
        return np.repeat(observation["state"][None], 50, axis=0)


def make_faulty():
    return Faulty()


def make_faulty_without_exit():
    return Faulty(exits=False)


def make_broken():
    raise ValueError("no weights here")


def make_exiting():
    os._exit(3)


class Gated(Faulty):
    """Holds, but answers its first call only once the file named by $ROBOFOLLOW_TEST_GATE
    exists (at most LIMIT seconds)."""

    def act(self, observation):
        waited = time.monotonic() + LIMIT
        while not Path(os.environ[GATE]).exists() and time.monotonic() < waited:
            time.sleep(0.05)
        return np.repeat(observation["state"][None], 50, axis=0)


def make_gated():
    return Gated()


# -- helpers ---------------------------------------------------------------------------------

def _command(out: Path, policy: str, tasks, *extra: str) -> list[str]:
    return [sys.executable, "-m", "robofollow.cli", "eval", "--policy", policy, "--out",
            str(out), "--specs", str(SPECS), "--tasks", ",".join(tasks), "--rounds", "1",
            "--quiet", *extra]


def _start(command: list[str], env: dict | None = None) -> subprocess.Popen:
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True,
                            env={**os.environ, **(env or {})})


def _finish(process: subprocess.Popen, limit: float = LIMIT) -> tuple[int, str, str]:
    """Its exit status, stdout and stderr; a command still running after `limit` seconds is
    killed (with its workers) and fails the test."""
    try:
        out, err = process.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.communicate()
        pytest.fail(f"hung: {' '.join(process.args[3:])} was still running after {limit} s")
    assert "Traceback" not in out + err, err
    return process.returncode, out, err


def _run(command: list[str], env: dict | None = None) -> tuple[int, str, str]:
    return _finish(_start(command, env))


def _records(out: Path) -> list[dict]:
    """Every line of RUN/episodes.jsonl (each must be a whole record)."""
    data = (out / "episodes.jsonl").read_bytes()
    assert not data or data.endswith(b"\n"), "a line cut short"
    return [json.loads(line) for line in data.split(b"\n")[:-1]]


def _once(records: list[dict]) -> dict[str, dict]:
    by_task = {r["task"]: r for r in records}
    assert len(by_task) == len(records), "an episode recorded twice"
    return by_task


def _main(capsys, *argv: str) -> tuple[int, str, str]:
    """`robofollow eval` in this process (for faults that cannot hang)."""
    from robofollow.cli import main

    status = main(["eval", *argv, "--specs", str(SPECS), "--rounds", "1", "--quiet"])
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return status, out, err


# -- 1. policies that die, exit or cannot be built ---------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("workers", ["1", "2"])
def test_a_policy_that_dies_or_exits_costs_its_episode_not_the_run(tmp_path, workers):
    out = tmp_path / "run"
    status, printed, _ = _run(_command(out, "tests.test_faults_eval:make_faulty", TASKS,
                                       "--workers", workers))
    assert status == 3  # finished, with policy failures
    assert "3 of 4 episodes ended in a policy failure" in printed
    assert "1 x the policy process exited with status 1 during the episode" in printed
    records = _once(_records(out))
    assert {task: r["error"] for task, r in records.items()} == EXPECTED_ERRORS
    assert records["scene1/L0/pickup_yellow_block_1_right"]["steps"] == 500
    summary = json.loads((out / "summary.json").read_text())
    assert summary["episodes"] == 4 and summary["policy_failures"]["episodes"] == 3
    # in-process policies get a time limit unless told otherwise
    assert json.loads((out / "run.json").read_text())["policy_timeout"] == 60.0


def test_in_process_a_systemexit_is_recorded_and_ctrl_c_still_stops(tmp_path, monkeypatch):
    from robofollow.compiled_cache import load
    from robofollow.eval.running.runner import EvalOptions, evaluate, read_results

    compiled = load(SPECS)
    tasks = ("scene1/L0/pickup_yellow_block_2", "scene1/L0/pickup_yellow_block_1_right")
    options = EvalOptions("tests.test_faults_eval:make_faulty_without_exit", ("scene1",),
                          ("L0",), 1, "normal", "none", compiled.spec.digest, tasks,
                          policy_timeout=60.0)
    result = evaluate(compiled, tmp_path / "run", options, workers=1, progress=False,
                      isolate=False)
    errors = {r["task"]: r["error"] for r in read_results(tmp_path / "run" / "episodes.jsonl")}
    assert errors == {tasks[0]: "step 0: the policy raised SystemExit(0)", tasks[1]: None}
    assert result["policy_failures"] == {
        "episodes": 1, "reasons": {"the policy raised SystemExit(0)": 1}}
    monkeypatch.setenv(GATE, "interrupt")  # the block_2 episode raises KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        evaluate(compiled, tmp_path / "stopped", options, workers=1, progress=False,
                 isolate=False)
    assert [r["task"] for r in read_results(tmp_path / "stopped" / "episodes.jsonl")] == [
        tasks[1]]  # what finished first (the compiled order) is kept, whole


@pytest.mark.slow
@pytest.mark.parametrize("factory, workers, message", [
    ("make_broken", "1", "the policy could not be built: ValueError: no weights here"),
    ("make_broken", "2", "the policy could not be built: ValueError: no weights here"),
    ("make_exiting", "1", "a worker process exited with status 3 while starting"),
])
def test_a_policy_that_cannot_be_built_stops_the_run_once_before_any_episode(
        tmp_path, factory, workers, message):
    policy = f"tests.test_faults_eval:{factory}"
    status, printed, err = _run(_command(tmp_path / "run", policy, TASKS,
                                         "--workers", workers))
    assert status == 1 and printed == ""
    assert err.strip() == f"error: --policy {policy!r}: {message}"  # one message
    assert _records(tmp_path / "run") == []


def test_a_dead_worker_is_charged_to_its_item_or_stops_the_run(tmp_path):
    from robofollow.workers import WorkerLost, results

    answers: dict = {}

    def consume(lost):
        try:
            answers["results"] = sorted(results(Dying, [1, 2, 3], 2, lost=lost), key=str)
        except WorkerLost as error:
            answers["error"] = str(error)

    for lost in (lambda item, what: f"{item}: {what}", None):
        answers.clear()
        thread = threading.Thread(target=consume, args=(lost,), daemon=True)
        thread.start()
        thread.join(LIMIT)
        assert not thread.is_alive(), "the supervised pool hung"
        if lost is not None:
            assert answers["results"] == [1, "2: exited with status 7", 3]
        else:
            assert answers["error"] == "a worker process exited with status 7 while working on 2"


class Dying:
    """A worker that exits on item 2."""

    def __call__(self, item):
        if item == 2:
            os._exit(7)
        return item

    def close(self):
        pass


# -- 2. outputs that cannot be written ---------------------------------------------------------

def _unwritable_folder(tmp_path: Path) -> Path:
    """A folder this process cannot write in: read-only by its mode, or (as root, whom modes
    do not stop) /sys, which the kernel keeps for itself."""
    if os.geteuid() != 0:
        folder = tmp_path / "read-only"
        folder.mkdir()
        folder.chmod(0o555)
        return folder
    folder = Path("/sys")
    try:
        os.mkdir(folder / "robofollow-probe")
    except OSError:
        return folder
    os.rmdir(folder / "robofollow-probe")
    pytest.skip("running as root with a writable /sys: no folder here refuses writes")


def test_outputs_that_cannot_be_written_are_refused_up_front(tmp_path, capsys):
    one = ["--policy", "noop", "--tasks", "scene1/L0/pickup_yellow_block_2"]
    deep = tmp_path / "missing" / "parents" / "run"  # missing parents are made
    assert _main(capsys, *one, "--out", str(deep))[0] == 0
    assert len(_records(deep)) == 1
    a_file = tmp_path / "a-file"
    a_file.write_text("x")
    for out, message in (
            (a_file, f"error: the run folder {a_file} is a file"),
            (a_file / "sub" / "run", f"error: cannot create the run folder {a_file}/sub/run: "
                                     f"{a_file} is a file"),
            (_unwritable_folder(tmp_path) / "run", "error: cannot ")):
        status, printed, err = _main(capsys, *one, "--out", str(out))
        assert (status, printed) == (1, "") and err.startswith(message), err
    assert a_file.read_text() == "x"


def test_a_disk_that_fills_mid_run_stops_it_with_whole_lines_and_it_resumes(tmp_path, capsys,
                                                                            monkeypatch):
    from robofollow.eval.running.run_folder import ResultsFile

    out, writes = tmp_path / "run", []
    original = ResultsFile.write

    def fills_up(self, data):
        writes.append(data)
        if len(writes) == 2:  # half the second line gets out, then the disk is full
            original(self, data[:len(data) // 2])
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        original(self, data)

    monkeypatch.setattr(ResultsFile, "write", fills_up)
    three = ",".join(list(TASKS)[1:])
    args = ["--policy", "noop", "--tasks", three, "--out", str(out), "--workers", "1"]
    status, _, err = _main(capsys, *args)
    assert status == 1
    assert f"error: cannot write {out / 'episodes.jsonl'}: No space left on device" in err
    assert "--resume" in err
    assert len(_records(out)) == 1  # whole lines only
    monkeypatch.setattr(ResultsFile, "write", original)
    assert _main(capsys, *args, "--resume")[0] == 0
    assert len(_once(_records(out))) == 3


def test_json_lines_are_split_at_newlines_only(tmp_path):
    from robofollow.eval.running.run_folder import ResultsFile, read_results

    record = {"episode": "scene1/L0/t\u2028x\u2029#r1", "scene": "scene1", "level": "L0",
              "task": "scene1/L0/t\u2028x\u2029",
              "intent_score": 0.0, "execution_score": 0.0, "complete": False}
    with ResultsFile(tmp_path / "episodes.jsonl") as sink:
        sink.append(record)
    data = (tmp_path / "episodes.jsonl").read_bytes()
    assert data.count(b"\n") == 1 and "\u2028".encode() not in data
    assert read_results(tmp_path / "episodes.jsonl") == [record]


# -- 3. a corrupt line in RUN/episodes.jsonl ---------------------------------------------------

def test_a_corrupt_line_stops_resume_with_its_number_and_drop_corrupt_moves_it(tmp_path,
                                                                              capsys):
    out = tmp_path / "run"
    three = ",".join(list(TASKS)[1:])
    args = ["--policy", "noop", "--tasks", three, "--out", str(out), "--workers", "1"]
    assert _main(capsys, *args)[0] == 0
    results = out / "episodes.jsonl"
    lines = results.read_bytes().split(b"\n")[:-1]
    corrupt = lines[1][:40] + b"\xff garbage"
    results.write_bytes(b"\n".join([lines[0], corrupt, lines[2], lines[0]]) + b"\n")
    before = results.read_bytes()
    status, printed, err = _main(capsys, *args, "--resume")
    assert (status, printed) == (1, "")
    assert f"error: {results} has 2 corrupt lines: line 2: not UTF-8 text" in err
    assert "line 4: repeats episode" in err and "--resume --drop-corrupt" in err
    assert results.read_bytes() == before  # nothing changed
    status, _, err = _main(capsys, *args, "--resume", "--drop-corrupt")
    assert status == 0 and "dropped 2 corrupt lines" in err
    assert sorted(_once(_records(out))) == sorted(list(TASKS)[1:])  # line 2's episode again
    assert (out / "episodes.jsonl.dropped").read_bytes() == corrupt + b"\n" + lines[0] + b"\n"


# -- 4. two runs on one folder ------------------------------------------------------------------

def _wait_for_lock(out: Path, process: subprocess.Popen) -> None:
    """Until `process` has written its id into RUN/.lock (it holds the lock)."""
    lock, deadline = out / ".lock", time.monotonic() + LIMIT
    while time.monotonic() < deadline and process.poll() is None:
        if lock.is_file() and lock.read_text().strip() == str(process.pid):
            return
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGKILL)
    pytest.fail(f"{process.args[3:]} never held {lock}: {process.communicate()}")


@pytest.mark.slow
def test_two_resumes_on_one_folder_one_waits_for_nothing_and_nothing_is_doubled(tmp_path):
    out, gate = tmp_path / "run", tmp_path / "gate"
    tasks = list(TASKS)[2:]
    command = _command(out, "tests.test_faults_eval:make_gated", tasks, "--workers", "1")
    env = {GATE: str(gate)}
    killed = _start(command, env)  # a run killed while it holds the lock: a stale lock
    _wait_for_lock(out, killed)
    os.killpg(killed.pid, signal.SIGKILL)
    killed.communicate()
    first = _start(command + ["--resume"], env)  # the stale lock does not block it
    _wait_for_lock(out, first)
    status, printed, err = _run(command + ["--resume"], env)  # at once, while `first` runs
    assert (status, printed) == (1, "")
    assert err.strip() == (f"error: {out} is in use by another robofollow eval (process "
                           f"{first.pid}); wait for it to end, or choose another folder")
    gate.touch()
    assert _finish(first)[0] == 0
    assert sorted(_once(_records(out))) == sorted(tasks)
