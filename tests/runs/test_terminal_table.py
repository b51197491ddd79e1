"""The study report in a terminal fits 120 columns: the compact table, and prose wrapped."""
from __future__ import annotations

from cistrack.studies.terminal_table import WIDTH, terminal_table, wrap_lines

COUNTED = ("tracking", "not-converged", "lost", "diverged")


def _row(filter_: str, iod: str) -> dict:
    return {"scenario": "example-1", "filter": filter_, "iod": iod, "runs": 100, "custody_kept": 97,
            "median_lost_day": 1.234567, "verdicts": "90/7/2/1", "pos_err_km": 1.23456789e10,
            "pos_err_km_p5": 1e-3, "pos_err_km_p95": 1e11, "anees_every_update": 6.02e10,
            "sigma_x_km": 1.5e-9, "sigma_y_km": 2.0e5, "sigma_z_km": 3.0, "wall_time_s": 123.456}


def test_the_table_of_long_names_and_large_numbers_fits_the_terminal():
    lines = terminal_table([_row("ukf-classic-iterated", "uniform-range-velocity-bound")] * 3, True, COUNTED)
    assert max(map(len, lines)) <= WIDTH
    assert any("uniform-range-velocity-bound" in line and "97/100" in line for line in lines)


def test_the_table_names_the_verdict_counts_it_shows():
    lines = terminal_table([_row("pgm", "noisy-range")], True, COUNTED)
    assert lines[-1].strip() == "verdicts: runs tracking / not-converged / lost / diverged"


def test_long_prose_lines_wrap_with_an_indent_and_keep_their_words():
    text = "- pgm with uniform-range-velocity-bound IOD on example-1 did not keep custody in " + "x " * 80
    out = wrap_lines([text])
    assert len(out) > 1 and max(map(len, out)) <= WIDTH and out[1].startswith("    ")
    assert " ".join(s.strip() for s in out).split() == text.split()
