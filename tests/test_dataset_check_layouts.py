"""`dataset check` reads meta/tasks.parquet in every layout LeRobot writes (a pandas frame of
task_index indexed by the task strings; the index named "task" since LeRobot 0.5, unnamed in
0.4.x) and reports a malformed one as a finding, not a traceback."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from robofollow.cli import main
from robofollow.data.check import check
from robofollow.data.generate import generate
from robofollow.data.units import Options
from tests.sim_helpers import benchmark

TASK = "pickup_yellow_block_1_left"


@pytest.fixture(scope="module")
def v30(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("v30") / "demos"
    options = Options("lerobot-v3.0", 1, (TASK,), 64, 48, "all", benchmark().spec.digest)
    generate(benchmark(), out, options, progress=False)
    return out


def _pandas_table(tasks: list[str], index_name: str | None) -> pa.Table:
    """What pandas' DataFrame({"task_index": ...}, index=pd.Index(tasks, name=index_name))
    .to_parquet() stores: the data column, then the index as a column ("__index_level_0__"
    when unnamed), with the pandas metadata naming it in index_columns."""
    field = index_name or "__index_level_0__"
    table = pa.table({"task_index": pa.array(range(len(tasks)), pa.int64()),
                      field: pa.array(tasks, pa.string())})
    column = {"field_name": field, "pandas_type": "unicode", "numpy_type": "object",
              "metadata": None}
    pandas = {"index_columns": [field],
              "column_indexes": [{"name": None, "field_name": None, "pandas_type": "unicode",
                                  "numpy_type": "object", "metadata": {"encoding": "UTF-8"}}],
              "columns": [{"name": "task_index", "field_name": "task_index",
                           "pandas_type": "int64", "numpy_type": "int64", "metadata": None},
                          {"name": index_name, **column}],
              "creator": {"library": "pyarrow", "version": pa.__version__},
              "pandas_version": "2.2.3"}
    return table.replace_schema_metadata({"pandas": json.dumps(pandas)})


def _copy_with_tasks(v30: Path, tmp_path: Path, make) -> Path:
    """A copy of the dataset whose tasks.parquet is `make(tasks)`, or the bytes it returns."""
    root = tmp_path / "copy"
    shutil.copytree(v30, root)
    path = root / "meta/tasks.parquet"
    tasks = pq.read_table(path).column("task").to_pylist()
    content = make(tasks)
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content is None:
        path.unlink()
    else:
        pq.write_table(content, path)
    return root


LAYOUTS = {
    "index named task (LeRobot >= 0.5)": lambda tasks: _pandas_table(tasks, "task"),
    "unnamed index (LeRobot 0.4.x)": lambda tasks: _pandas_table(tasks, None),
    "index of another name": lambda tasks: _pandas_table(tasks, "instruction"),
    "plain columns, no pandas metadata": lambda tasks: pa.table(
        {"task": tasks, "task_index": pa.array(range(len(tasks)), pa.int64())}),
}


@pytest.mark.slow
@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_every_tasks_parquet_layout_lerobot_writes_validates(v30, tmp_path, capsys, layout):
    root = _copy_with_tasks(v30, tmp_path, LAYOUTS[layout])
    report = check(root)
    assert report.ok, report.errors
    assert report.episodes > 1  # one episode per paraphrase, every task looked up
    assert main(["dataset", "check", str(root)]) == 0
    assert "valid" in capsys.readouterr().out


MALFORMED = {
    "no task strings": (lambda tasks: pa.table({"task_index": range(len(tasks))}),
                        "meta/tasks.parquet: expected a task_index column and the task strings "
                        "in a 'task' column or as the pandas index"),
    "no task_index": (lambda tasks: pa.table({"task": tasks}),
                      "found columns ['task']"),
    "tasks are numbers": (lambda tasks: pa.table({"task": range(len(tasks)),
                                                  "task_index": range(len(tasks))}),
                          "expected string tasks and integer task_index, got task int64"),
    "not parquet": (lambda tasks: b"task,task_index\n", "meta/tasks.parquet: unreadable"),
    "missing": (lambda tasks: None, "meta/tasks.parquet: unreadable"),
}


@pytest.mark.slow
@pytest.mark.parametrize("damage", list(MALFORMED))
def test_a_malformed_tasks_parquet_is_a_finding_not_a_traceback(v30, tmp_path, capsys, damage):
    make, finding = MALFORMED[damage]
    root = _copy_with_tasks(v30, tmp_path, make)
    report = check(root)
    assert any(finding in error for error in report.errors), report.errors
    assert main(["dataset", "check", str(root)]) == 1
    out = capsys.readouterr()
    assert finding in out.out and "Traceback" not in out.out + out.err


def _with_list_vectors(v30: Path, tmp_path: Path, short_row: bool = False) -> Path:
    """A copy whose state and action are plain list<float> columns, as LeRobot's v2.1 -> v3.0
    converter writes them (one row cut to 13 values with `short_row`)."""
    root = tmp_path / "lists"
    shutil.copytree(v30, root)
    for path in sorted((root / "data").rglob("*.parquet")):
        table = pq.read_table(path)
        for key in ("observation.state", "action"):
            rows = table.column(key).to_pylist()
            if short_row:
                rows[1] = rows[1][:13]
            table = table.set_column(table.column_names.index(key), key,
                                     pa.array(rows, pa.list_(pa.float32())))
        pq.write_table(table, path)
    return root


@pytest.mark.slow
def test_state_and_action_as_plain_lists_of_14_floats_validate(v30, tmp_path):
    report = check(_with_list_vectors(v30, tmp_path))
    assert report.ok, report.errors


@pytest.mark.slow
def test_a_plain_list_row_of_another_width_is_a_finding(v30, tmp_path):
    errors = check(_with_list_vectors(v30, tmp_path, short_row=True)).errors
    assert errors and any("observation.state is list<element: float>, expected "
                          "fixed_size_list<float>[14] (or a list of 14 floats a row)" in e
                          for e in errors), errors
