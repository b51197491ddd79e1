"""A fit that rejects every observation of one site says so, naming the site (probe J6).

The data: a survey set of an NRHO seen from M22, 711 and J04, whose 14 observations from 711 state
rmsRA/rmsDec of 0.0011" (1.1 mas) while their noise is 0.885", as the other sites state. All of
them had been rejected without a word, under "converged; well determined ... from 2 sites"."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from cistrack.fitting.fit_summary import rejected_site_lines, summary_lines
from cistrack.least_squares.residual_table import ResidualTable

DATA = Path(__file__).parent / "data" / "one_site_states_1mas.psv"


def test_a_fit_rejecting_all_of_one_sites_observations_names_the_site_and_its_stated_uncertainties(tmp_path):
    from cistrack.fitting.from_observations import fit_files

    [one] = fit_files([DATA], out=tmp_path / "fit")
    text = " ".join(line.strip() for line in summary_lines(one))
    assert "warning: all 14 observations of site 711 (34 % of the data) were rejected" in text
    assert "they state 0.0011\" against 0.89\" at the other sites, which looks far too small" in text
    assert "check 711's stated uncertainties (rmsRA/rmsDec)" in text


def _table(sites: list[str], sigma: list[float], rejected: list[bool]) -> ResidualTable:
    o_c = np.ones((len(sites), 2))
    normalised = o_c / np.asarray(sigma)[:, None]
    return ResidualTable(times=np.arange(len(sites), dtype=float), sites=np.array(sites), kinds=np.array(["radec"] * len(sites)),
                         names=("right_ascension", "declination"), units=("arcsec", "arcsec"), o_c=o_c,
                         normalised=normalised, chi2=np.sum(normalised ** 2, axis=1), rejected=np.array(rejected))


def test_a_site_with_one_or_two_rejected_observations_is_no_finding():
    table = _table(["A", "A", "B", "B", "B"], [1.0] * 5, [True, True, False, False, False])
    assert rejected_site_lines(table) == []


def test_a_site_rejected_whole_with_ordinary_uncertainties_is_named_without_blaming_them():
    table = _table(["A"] * 3 + ["B"] * 3, [1.0] * 6, [True] * 3 + [False] * 3)
    [line] = rejected_site_lines(table)
    assert "all 3 observations of site A (50 % of the data) were rejected" in line and "too small" not in line
