"""The post-fit residual table: RA residuals on the sky (times cos Dec), arcsec, normalised
residuals, per-observation chi-square and rejected flags, one row per observation."""
from __future__ import annotations

import numpy as np

from cistrack.least_squares import fit_orbit
from cistrack.least_squares.residual_table import residual_table
from cistrack.units import ARCSEC_RAD

from .arcs import GUESS_OFFSET, cr3bp_arc


def _table(kind: str):
    values = np.array([[1.0, np.radians(60.0)], [2.0, np.radians(-30.0)]])
    resid = np.array([[2.0, 1.0], [-4.0, 3.0]]) * ARCSEC_RAD
    sig = np.full((2, 2), 0.5 * ARCSEC_RAD)
    names = ("right_ascension", "declination") if kind == "radec" else ("azimuth", "elevation")
    return residual_table(np.array([0.1, 0.2]), np.array(["568", "J04"]), np.array([kind, kind]), names,
                          values, resid, sig, np.array([False, True]))


def test_ra_residual_is_given_on_the_sky_times_cos_dec_in_arcsec():
    t = _table("radec")
    np.testing.assert_allclose(t.o_c[:, 0], [2.0 * 0.5, -4.0 * np.cos(np.radians(30.0))])
    np.testing.assert_allclose(t.o_c[:, 1], [1.0, 3.0])
    assert t.column_names() == ("ra_cos_dec_arcsec", "declination_arcsec")


def test_az_el_residuals_are_plain_arcsec():
    t = _table("azel")
    np.testing.assert_allclose(t.o_c, [[2.0, 1.0], [-4.0, 3.0]])


def test_normalised_residuals_and_chi2_use_the_components_own_sigma():
    t = _table("radec")
    np.testing.assert_allclose(t.normalised, [[4.0, 2.0], [-8.0, 6.0]])
    np.testing.assert_allclose(t.chi2, [20.0, 100.0])


def test_rows_hold_time_site_residuals_normalised_residuals_and_the_rejected_flag():
    rows = _table("radec").rows()
    assert rows[1]["site"] == "J04" and rows[1]["rejected"] is True and rows[0]["rejected"] is False
    assert set(rows[0]) == {"t_tu", "site", "kind", "o_c_ra_cos_dec_arcsec", "o_c_declination_arcsec",
                            "norm_right_ascension", "norm_declination", "chi2", "rejected"}


def test_rms_leaves_out_rejected_observations():
    t = _table("radec")
    np.testing.assert_allclose(t.rms(), [1.0, 1.0])


def test_fit_result_has_one_row_per_observation():
    arc = cr3bp_arc()
    res = fit_orbit(arc.dynamics, arc.sensor, arc.noisy(3), arc.truth0 + GUESS_OFFSET, 0.0)
    assert len(res.residuals) == len(arc.times) and res.residuals.names == ("azimuth", "elevation")
    np.testing.assert_array_equal(res.residuals.times, arc.times)
    assert np.isclose(np.sum(res.residuals.chi2[~res.residuals.rejected]), res.chi2)
