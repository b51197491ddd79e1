"""``Run.plot()`` of a run whose metrics become NaN (a filter whose belief turned NaN): the lines stop,
each panel says after which step its quantity is undefined, and numpy's warnings do not leak."""
from __future__ import annotations

import warnings

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

from cistrack.studies.run_figure import plot_run, undefined_after

N = 8


def _steps(nan_from: int) -> pd.DataFrame:
    """The columns of steps.parquet a plot reads, every metric NaN from step ``nan_from`` on."""
    d = pd.DataFrame({"step": np.arange(N), "kind": ["iod"] + ["update"] * (N - 2) + ["predict"],
                      "t_days": np.linspace(1.0, 3.0, N), "pos_err_km": np.linspace(100.0, 10.0, N),
                      "sigma_pos_km": np.linspace(50.0, 5.0, N), "sigma_x_km": np.linspace(30.0, 3.0, N),
                      "sigma_y_km": np.linspace(20.0, 2.0, N), "sigma_z_km": np.linspace(10.0, 1.0, N),
                      "nees": np.full(N, 5.0), "entropy": np.linspace(10.0, 5.0, N)})
    d.loc[nan_from:, "pos_err_km":] = np.nan
    return d


@pytest.fixture
def nan_figure():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fig = plot_run(_steps(nan_from=3), {"verdict": {"kind": "diverged"}}, "nan-run")
    yield fig
    plt.close(fig)


def test_plotting_a_run_with_nan_metrics_raises_no_warning(nan_figure):
    assert len(nan_figure.axes) == 4


def test_each_panel_says_after_which_step_its_quantity_is_undefined(nan_figure):
    notes = [[t.get_text() for t in ax.texts] for ax in nan_figure.axes]
    assert notes == [["undefined (NaN) after step 2"]] * 4


def test_a_quantity_missing_only_on_rows_of_a_kind_it_never_has_is_not_undefined():
    """A NIS exists at updates only: the final predict step without one is not a NaN NIS."""
    steps = pd.DataFrame({"step": [0, 1, 2, 3], "kind": ["iod", "update", "update", "predict"]})
    assert undefined_after(steps, "nis", np.array([np.nan, 2.0, 1.5, np.nan])) is None
