"""The summary ``cistrack run`` prints gives every velocity in m/s (sigmas and errors alike) and
says so in its header; the stored summary keeps its keys and units (``sigma_vx_cms`` in cm/s)."""
from __future__ import annotations

import contextlib
import io
import json
import re

import pytest

from cistrack.cli.main import main
from cistrack.evaluation.run_summary import final_lines

NUMBER = r"[-+0-9.e]+"


@pytest.fixture(scope="module")
def printed(tmp_path_factory):
    out = tmp_path_factory.mktemp("units") / "run"
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        assert main(["run", "quick", "--set", "duration_days=1.5", "--set", "iod.n_particles=300",
                     "--set", "filter.n_particles=300", "--out", str(out)]) == 0
    final = json.loads((out / "manifest.json").read_text())["summary"]["final"]
    return stdout.getvalue().splitlines(), final


def test_no_printed_line_uses_cm_per_s(printed):
    lines, _ = printed
    assert [line for line in lines if "cm/s" in line] == []


def test_the_final_block_states_its_units_in_its_header(printed):
    lines, _ = printed
    assert "  final state (positions in km, velocities in m/s):" in lines


def test_the_printed_velocity_sigmas_are_the_stored_cm_per_s_ones_in_m_per_s(printed):
    lines, final = printed
    row = next(line for line in lines if "per-axis sigma" in line)
    shown = [float(v) for v in re.search(rf"velocity ({NUMBER}) / ({NUMBER}) / ({NUMBER}) m/s", row).groups()]
    stored = [final[k] for k in ("sigma_vx_cms", "sigma_vy_cms", "sigma_vz_cms")]
    assert shown == pytest.approx([v / 100 for v in stored], rel=5e-3)


def test_sigma_and_error_velocities_share_one_unit():
    final = {"sigma_x_km": 1.0, "sigma_y_km": 2.0, "sigma_z_km": 3.0, "sigma_vx_cms": 150.0,
             "sigma_vy_cms": 20.0, "sigma_vz_cms": 3.0, "pos_err_km": 4.0, "vel_err_ms": 0.5, "nees": 5.0, "entropy": 1.0}
    text = "\n".join(final_lines(final, lambda v: "-" if v is None else f"{v:g}"))
    assert "velocity 1.5 / 0.2 / 0.03 m/s" in text and "velocity 0.5 m/s" in text
    assert "cm/s" not in text
