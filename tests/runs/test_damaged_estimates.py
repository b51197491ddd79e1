"""`cistrack export` and `cistrack predict` refuse a run whose estimates table holds no rows,
a NaN mean or covariance, or a step twice, naming the file or folder and what is wrong: never a
traceback, a hidden temporary file, a blamed dynamics component, or `nan` written into an OEM
with exit 0 (probe H1, H2, H3). Real run of the quick scenario, its table edited with pyarrow."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cistrack.cli.main import main



def _edited(finished: Path, tmp_path: Path, edit) -> Path:
    """A copy of ``finished`` whose estimates table is ``edit(table)``."""
    import pyarrow.parquet as pq

    d = tmp_path / "run"
    shutil.copytree(finished, d, ignore=shutil.ignore_patterns(".run.lock"))
    pq.write_table(edit(pq.read_table(d / "estimates.parquet")), d / "estimates.parquet")
    return d


def _last_row_nan(column: str):
    def edit(table):
        import pyarrow as pa

        rows = table.to_pylist()
        rows[-1][column] = [float("nan")] * len(rows[-1][column])
        return pa.Table.from_pylist(rows, schema=table.schema)
    return edit


def _refusals(d: Path, tmp_path: Path, capsys) -> list[str]:
    """The error lines of export and predict on ``d``; both must exit 2 and write nothing."""
    assert main(["export", str(d), "--out", str(tmp_path / "x.oem")]) == 2
    assert main(["predict", str(d), "--site", "711", "--out", str(tmp_path / "pr")]) == 2
    assert not (tmp_path / "x.oem").exists() and not (tmp_path / "pr").exists()
    err = capsys.readouterr().err
    assert "Traceback" not in err and ".tmp" not in err
    return [line for line in err.splitlines() if "error:" in line]


def test_an_empty_estimates_table_is_refused_by_export_and_predict_naming_the_file(finished_quick_run, tmp_path, capsys):
    d = _edited(finished_quick_run, tmp_path, lambda t: t.slice(0, 0))
    for line in _refusals(d, tmp_path, capsys):
        assert f"{d / 'estimates.parquet'}: holds no estimates; run the scenario again into {d} with --overwrite" in line


@pytest.mark.parametrize("column", ["mean_km", "covariance_km", "weights"])
def test_a_nan_in_the_estimates_is_refused_as_damaged_never_written_as_nan(finished_quick_run, tmp_path, column, capsys):
    d = _edited(finished_quick_run, tmp_path, _last_row_nan(column))
    lines = _refusals(d, tmp_path, capsys)
    assert len(lines) == 2
    for line in lines:
        assert f"{d}: its estimates are damaged (step " in line and f"'s {column} holds NaN or inf" in line
        assert "dynamics" not in line and "fit.json" not in line


def test_a_step_written_twice_is_refused_rather_than_exported_with_a_wrong_count(finished_quick_run, tmp_path, capsys):
    import pyarrow as pa

    d = _edited(finished_quick_run, tmp_path, lambda t: t.take(pa.array([*range(t.num_rows), t.num_rows - 1])))
    for line in _refusals(d, tmp_path, capsys):
        assert "its estimates are damaged (step " in line and "appears 2 times" in line


def test_the_unedited_run_still_exports_finite_numbers(finished_quick_run, tmp_path):
    out = tmp_path / "x.oem"
    assert main(["export", str(finished_quick_run), "--out", str(out)]) == 0
    assert "nan" not in out.read_text().lower()


def test_a_non_finite_prediction_advises_writing_the_folder_again_not_only_refitting_a_fit_json():
    from cistrack.errors import ConfigError
    from cistrack.fitting.fit_export import refuse_non_finite

    with pytest.raises(ConfigError) as err:
        refuse_non_finite(np.array([[1.0], [np.inf]]), ["2026-01-03T00:00:00", "2026-01-03T01:00:00"], "the sky predictions")
    assert "1 of 2 times" in str(err.value) and "a run's last estimate" in str(err.value)
    assert "'cistrack run' into it with --overwrite" in str(err.value)
