"""Results rows become the table pyarrow's own converter makes, without importing pandas."""
from __future__ import annotations

import struct
import subprocess
import sys

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from cistrack.results.arrow_rows import table_from_rows
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario


def _reference(rows):
    keys = list(dict.fromkeys(k for r in rows for k in r))
    return pa.Table.from_pydict({k: [r.get(k) for r in rows] for k in keys})


def _bits(v):
    """A value with every float replaced by its bit pattern (NaN equals NaN, -0.0 differs from 0.0)."""
    if isinstance(v, float):
        return ("float", struct.pack("<d", v))
    if isinstance(v, list):
        return [_bits(x) for x in v]
    return v


def _identical(a: pa.Table, b: pa.Table) -> bool:
    return a.schema == b.schema and all(
        _bits(a.column(i).to_pylist()) == _bits(b.column(i).to_pylist()) for i in range(a.num_columns))


def _same(rows):
    got, want = table_from_rows(rows), _reference(rows)
    assert _identical(got, want)
    return got


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("arrow") / "run"
    scen = load_scenario("quick").with_overrides({"duration_days": 1.4, "filter": {"n_particles": 300, "n_components": 2},
                                                  "iod": {"n_particles": 300}})
    run_scenario(scen, seed=1, output_dir=out)
    return out


@pytest.mark.parametrize("table", ["steps.parquet", "estimates.parquet"])
def test_a_real_runs_rows_give_pyarrows_table(run_dir, table):
    written = pq.read_table(run_dir / table)
    rows = written.to_pylist()
    assert _identical(_same(rows), written)


def test_nulls_missing_keys_and_special_floats_match():
    rows = [{"a": 1.5, "b": 2, "s": "x", "l": [1.0, 2.0], "flag": True},
            {"a": None, "b": None, "s": None, "l": None, "flag": None, "late": "é"},
            {"a": float("nan"), "b": -(2 ** 63), "s": "", "l": [], "flag": False},
            {"a": float("inf"), "b": 2 ** 63 - 1, "s": "ünïcode", "l": [float("nan"), -0.0]}]
    t = _same(rows)
    assert t.column("a").null_count == 1 and np.isnan(t.column("a")[2].as_py())


def test_mixed_ints_and_floats_become_doubles():
    _same([{"x": 1}, {"x": 2.5}, {"x": None}, {"x": np.int64(-3)}, {"x": np.float64(4.25)}])
    _same([{"v": [1, 2]}, {"v": [3.5]}])


def test_lists_of_ints_stay_integer_lists():
    assert _same([{"v": [1, 2]}, {"v": [3]}, {"v": None}]).schema.field("v").type == pa.list_(pa.int64())


def test_columns_it_does_not_build_are_left_to_pyarrow():
    for rows in ([{"x": True}, {"x": 1}],                 # bool and int
                 [{"x": 1}, {"x": "a"}],                  # number and string
                 [{"x": [1.0, None]}],                    # a null inside a list
                 [{"x": [[1.0]]}],                        # nested lists
                 [{"x": []}, {"x": []}],                  # only empty lists
                 [{"x": np.float32(1.5)}],                # another numpy width
                 [{"x": 2 ** 63}],                        # beyond int64
                 [{"x": 2 ** 60}, {"x": 0.5}],            # an int a double cannot hold, mixed
                 [{"x": None}, {"x": None}]):              # only nulls
        try:
            want = _reference(rows)
        except (pa.ArrowInvalid, pa.ArrowTypeError, OverflowError):
            with pytest.raises((pa.ArrowInvalid, pa.ArrowTypeError, OverflowError)):
                table_from_rows(rows)
            continue
        assert _identical(table_from_rows(rows), want)


def test_random_rows_match(rng):
    for _ in range(50):
        n = int(rng.integers(1, 30))
        rows = []
        for _ in range(n):
            row = {}
            if rng.random() < 0.8:
                row["f"] = None if rng.random() < 0.2 else float(rng.normal() * 10.0 ** int(rng.integers(-300, 300)))
            if rng.random() < 0.8:
                row["i"] = None if rng.random() < 0.2 else int(rng.integers(-2 ** 62, 2 ** 62))
            if rng.random() < 0.8:
                row["s"] = None if rng.random() < 0.2 else "".join(rng.choice(list("abcé漢 ")) for _ in range(int(rng.integers(0, 6))))
            if rng.random() < 0.8:
                row["l"] = None if rng.random() < 0.2 else rng.normal(size=int(rng.integers(1, 5))).tolist()
            if rng.random() < 0.5:
                row["b"] = None if rng.random() < 0.2 else bool(rng.random() < 0.5)
            rows.append(row)
        if any(rows):
            _same(rows)


def test_writing_a_run_does_not_import_pandas(tmp_path):
    code = ("import sys\n"
            "from cistrack.runs.pipeline import run_scenario\n"
            "from cistrack.scenario.loading import load_scenario\n"
            "scen = load_scenario('quick').with_overrides({'duration_days': 1.4, 'filter': {'n_particles': 200, "
            "'n_components': 2}, 'iod': {'n_particles': 200}})\n"
            f"run_scenario(scen, seed=1, output_dir={str(tmp_path / 'out')!r})\n"
            "assert (__import__('pathlib').Path(" + repr(str(tmp_path / "out")) + ") / 'steps.parquet').exists()\n"
            "print('pandas' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "False"
