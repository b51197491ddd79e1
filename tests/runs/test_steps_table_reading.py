"""A run's steps table read back names what is wrong with an edited one: without a ``t_days`` column
it is "not a steps table (no column t_days)", never "the run has no steps" when it has eleven; rows
stored out of order come back in step order, as export and predict sort theirs (probe H6)."""
from __future__ import annotations

import shutil
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

import cistrack as ct
from cistrack.errors import CistrackError


def _edited_steps(run: Path, tmp_path: Path, edit) -> Path:
    d = tmp_path / "run"
    shutil.copytree(run, d, ignore=shutil.ignore_patterns(".run.lock"))
    pq.write_table(edit(pq.read_table(d / "steps.parquet")), d / "steps.parquet")
    return d


@pytest.mark.parametrize("edit", [lambda t: t.drop(["t_days"]),
                                  lambda t: t.rename_columns(["T_days" if c == "t_days" else c for c in t.column_names])],
                         ids=["dropped", "renamed"])
def test_a_steps_table_without_t_days_is_named_as_such_by_steps_and_plot(finished_quick_run, tmp_path, edit):
    d = _edited_steps(finished_quick_run, tmp_path, edit)
    r = ct.read_run(d)
    for reading in (lambda: r.steps, r.plot):
        with pytest.raises(CistrackError) as err:
            reading()
        assert str(err.value).startswith(f"{d / 'steps.parquet'}: not a steps table (no column t_days)")


def test_steps_stored_in_reverse_come_back_in_step_order(finished_quick_run, tmp_path):
    d = _edited_steps(finished_quick_run, tmp_path, lambda t: t.take(pa.array(range(t.num_rows - 1, -1, -1))))
    assert ct.read_run(d).steps["step"].tolist() == ct.read_run(finished_quick_run).steps["step"].tolist()
    assert ct.read_run(d).steps["step"].is_monotonic_increasing
