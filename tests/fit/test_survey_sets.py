"""Survey-cadence sets (examples/survey-sets): the generator keeps the cadence it promises, and
`cistrack fit` with no option recovers each orbit family from them (slow): converged, the truth
inside the exported covariance at every OEM epoch of the arc (Mahalanobis^2 <= 22.5), every
injected outlier rejected and at most one clean observation (or 5 %) rejected with them, and
no observation left out (the arc is one orbit).

The first night is one tracklet of 3-5 exposures: the kinematic-fit IOD needs 8 in the first
pass, so these fits start from the tracklet-ranging IOD that `cistrack fit` falls back on
(commit e875bed). Before it, every case here failed at the IOD.
"""
from __future__ import annotations

import json
import re
from datetime import datetime, timedelta
import sys
from pathlib import Path

import numpy as np
import pytest

from cistrack.astro.sites import observatory
from cistrack.runs.observation_files import read_observations
from cistrack import units

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "survey-sets"
sys.path.insert(0, str(EXAMPLES))
from check_survey_fit import MAHALANOBIS2_BOUND, check_set  # noqa: E402
from make_survey_sets import FAMILIES, make  # noqa: E402

_EPOCH = "2000-01-01T00:00:00Z"


def _tracklets(times_s: np.ndarray, sites: np.ndarray) -> list[tuple[float, float, int, str]]:
    """(start s, span s, exposures, site) of runs of one site's exposures less than 40 min apart."""
    out: list[list] = []
    for t, s in zip(times_s, sites):
        if out and out[-1][3] == s and t - out[-1][4] < 2400.0:
            out[-1][1], out[-1][2], out[-1][4] = t - out[-1][0], out[-1][2] + 1, t
        else:
            out.append([t, 0.0, 1, s, t])
    return [(a, b, c, d) for a, b, c, d, _e in out]


@pytest.mark.parametrize("family", ["heo", "dro"])
def test_generator_keeps_the_survey_cadence(tmp_path, family):
    info = make(tmp_path / family, family, seed=2)
    ms = read_observations(tmp_path / family / "observations.psv", _EPOCH)
    t = ms.times * units.TU_S
    tracks = _tracklets(t, ms.sites)
    assert all(3 <= n <= 5 for _a, _b, n, _s in tracks), tracks
    assert all(span <= 31 * 60 for _a, span, _n, _s in tracks), tracks
    first = tracks[0]
    assert first[2] == info["first_night_exposures"] and 9 * 60 <= first[1] <= 31 * 60
    assert tracks[1][0] - first[0] > 12 * 3600.0, "the first night holds one lone tracklet"
    lats = [observatory(s).latitude_deg for s in info["sites"]]
    assert min(lats) < 0 < max(lats) and 2 <= len(lats) <= 3
    assert 7 <= (t[-1] - t[0]) / 86400.0 <= 22
    assert len(info["outliers"]) == max(1, round(0.03 * len(ms)))
    np.testing.assert_allclose(ms.sigmas[:, 1] / units.ARCSEC_RAD, info["sigma_arcsec"], rtol=1e-9)
    assert 0.5 <= info["sigma_arcsec"] <= 1.0
    if family == "heo":
        assert 60_000.0 < info["range_km_first"] < 84_328.0  # below the IOD's default range floor
    again = make(tmp_path / "again", family, seed=2)
    assert again == info
    assert (tmp_path / "again" / "observations.psv").read_bytes() == (tmp_path / family / "observations.psv").read_bytes()


def test_a_burned_set_is_the_same_set_until_its_burn_and_another_orbit_after_it(tmp_path):
    plain, burned = make(tmp_path / "plain", "nrho", 1), make(tmp_path / "burned", "nrho", 1, burn_ms=0.5)
    assert "burn" not in plain and burned["burn"]["delta_v_ms"] == 0.5
    assert np.linalg.norm(burned["burn"]["delta_v_vector_ms"]) == pytest.approx(0.5)
    a, b = (read_observations(tmp_path / d / "observations.psv", _EPOCH) for d in ("plain", "burned"))
    t_burn = units.utc_to_tu(units.parse_utc(_EPOCH), units.parse_utc(burned["burn"]["utc"]))
    before, after = a.times < t_burn, a.times > t_burn
    assert before.sum() >= 2 and after.sum() >= 2  # a night or more on each side
    np.testing.assert_array_equal(a.values[before], b.values[before])
    assert np.all(np.abs(a.values[after] - b.values[after]).max(axis=1) > 0)


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_fit_recovers_each_family(tmp_path, family):
    set_dir = tmp_path / f"{family}-s1"
    info = make(set_dir, family, seed=1)
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert row.n_fitted == row.n_observations == info["n_observations"], "observations left out of the fit"
    assert len(row.m2) > 0 and max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2
    assert row.rejected_injected == row.injected == len(info["outliers"])
    assert row.clean_rejected <= row.max_clean_rejected, f"{row.clean_rejected} clean observations rejected"
    assert json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["converged"]


def _clean_fit(set_dir, info: dict, tmp_path) -> tuple:
    """(row, fit.json's messages) of ``cistrack fit`` on the set, asserted converged with every
    observation fitted and the truth within :data:`MAHALANOBIS2_BOUND` at each epoch."""
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert row.n_fitted == row.n_observations == info["n_observations"]
    assert len(row.m2) > 0 and max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2
    return row, json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["messages"]


@pytest.mark.slow
def test_halo_seed_33_is_not_seeded_from_a_false_minimum(tmp_path):
    """Halo seed 33 (a 3-exposure first night, then tracklets two and three days later): the first
    tracklet's ranging fit converged with residuals 57 times the noise, 139,000 km off, and from that
    seed the fit ended FAILED (weighted RMS 289,069); the next seed's fit is clean."""
    set_dir = tmp_path / "halo-s33"
    info = make(set_dir, "halo", seed=33)
    row, messages = _clean_fit(set_dir, info, tmp_path)
    assert any("tracklet 1's fit converged with residuals" in m and "a false minimum" in m for m in messages)


def test_an_observation_at_the_threshold_that_cycles_between_passes_is_kept_rejected(tmp_path):
    """nrho seed 208 (unseen until session 40): one observation was rejected in one pass and
    readmitted in the next (chi-square just above, then just below the threshold), the rejected
    set cycled, and the fit was reported not converged (RMS 1.06) and FAILED as a possible maneuver.
    Kept rejected, the fit converges; the injected outlier is rejected too."""
    set_dir = tmp_path / "nrho-s208"
    info = make(set_dir, "nrho", seed=208)
    row, messages = _clean_fit(set_dir, info, tmp_path)
    assert row.rejected_injected == row.injected
    assert any("1 observation(s) at the threshold, rejected in one pass and readmitted in the next, are kept "
               "rejected" in m for m in messages)


@pytest.mark.slow
def test_a_fourth_tracklet_eleven_days_after_the_third_does_not_stop_the_ranging(tmp_path):
    """Halo seed 173 with 5 exposures a tracklet: three tracklets on three nights, the fourth 11.6
    days later. Every seed scored on the other three gave no converged fit (8 seeds, 48 fits) and
    the fit FAILED; scored on the two within 6 days, the ranging finds the orbit."""
    set_dir = tmp_path / "halo-s173"
    info = make(set_dir, "halo", seed=173, exposures=5)
    assert info["tracklets"] == 4
    row, messages = _clean_fit(set_dir, info, tmp_path)
    assert row.rejected_injected == row.injected
    assert any("only the tracklets within 6 days scored it" in m for m in messages)


@pytest.mark.slow
def test_mis_identified_tracklets_at_the_arcs_end_are_no_burn(tmp_path):
    """The last 7 observations of nrho seed 31 moved by 0.02 deg RA, 0.01 deg Dec (two tracklets of
    one night): the fit had kept a 532 +- 24,668 m/s burn and said "converged", the truth 3,454 km
    away. A burn that cannot be told from none is no maneuver: the fit is reported not clean, either
    because the burn the search keeps is within 3 sigma of none or because no burn is kept at all."""
    from cistrack.cli.main import main

    make(tmp_path / "set", "nrho", seed=31)
    lines = (tmp_path / "set" / "observations.psv").read_text().splitlines()
    head, rows = lines[:2], lines[2:]
    moved = []
    for row in rows[-7:]:
        f = row.split("|")
        f[4], f[5] = repr(float(f[4]) + 0.02), repr(float(f[5]) + 0.01)
        moved.append("|".join(f))
    (tmp_path / "end7.psv").write_text("\n".join(head + rows[:-7] + moved) + "\n")
    assert main(["fit", str(tmp_path / "end7.psv"), "--out", str(tmp_path / "fit"), "--quiet"]) == 3
    record = json.loads((tmp_path / "fit" / "fit.json").read_text())
    assert not record["converged"] and not record.get("maneuvers")
    assert any(m.startswith("not a clean fit") and ("within 3 sigma of none" in m or "no impulsive burn" in m)
               for m in record["messages"]), record["messages"]


@pytest.mark.slow
def test_a_burn_in_a_gap_the_first_screen_ranks_below_a_nights_gap_is_placed_in_its_gap(tmp_path):
    """dro seed 90 with a 0.5 m/s burn in a four-day gap: the linearised screen about the ballistic
    compromise ranked that gap best but placed the burn too early in it, so its full fit lost to a
    50-minute gap between two tracklets 1.4 days later, and the fit reported the burn there, time
    49 sigma off. Screened again about the fit with the burn, the gap is fitted again from there."""
    set_dir = tmp_path / "dro-s90"
    info = make(set_dir, "dro", seed=90, burn_ms=0.5)
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert info["burn"]["delta_v_ms"] == 0.5
    assert row.burns.startswith("1:") and row.burn_ok, row.burns  # one burn, time and size within 3 sigma
    assert max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2


@pytest.mark.slow
def test_a_burn_once_fitted_a_night_early_is_measured_or_not_reported(tmp_path):
    """nrho seed 143 with a 0.5 m/s burn: the search once kept 3.7 +- 0.6 m/s a night before the
    truth, the fit with it rejecting 8 of 75 observations, and reported it converged and clean, the
    truth at Mahalanobis^2 515,846; more rejections than outliers explain made it not clean. Moved
    fits that keep the estimate's rejections (session of 2026-11-30) measure it: 0.483 +- 0.021 m/s,
    time z +1.5. Either is honest; a clean fit with the truth outside is not."""
    set_dir = tmp_path / "nrho-s143"
    make(set_dir, "nrho", seed=143, burn_ms=0.5)
    row = check_set(set_dir, tmp_path / "fits")
    record = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())
    if not _measured_when_clean(row):
        assert not record["converged"] and not record.get("maneuvers")


@pytest.mark.slow
def test_a_burn_timed_in_a_narrow_minimum_has_a_sigma_that_reaches_the_time_the_arc_allows(tmp_path):
    """nrho seed 99 with a 0.5 m/s burn after a night's last tracklet: the search timed it between
    the night's two tracklets, 4.4 hours early +- 11 minutes (z -24.7); a burn after the night's
    last fits as well, and the time's sigma now reaches it."""
    set_dir = tmp_path / "nrho-s99"
    make(set_dir, "nrho", seed=99, burn_ms=0.5)
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert row.burns.startswith("1:") and row.burn_ok, row.burns


@pytest.mark.slow
def test_a_burn_placed_after_the_first_night_where_another_gap_fits_better_is_not_reported(tmp_path):
    """heo seed 90 with a 0.5 m/s burn 5.2 days in: the search puts a 3.2 m/s burn after the first
    night (time z -16.9). Judged at each allowed time its size is 5 sigma, and the fit had been
    called converged, the truth at Mahalanobis^2 900; a burn in the five-day gap that holds the
    true one fits with a cost 29 lower. Every night's gap is now tried: a burn within 3 sigma of
    the truth, or a fit that is not clean."""
    set_dir = tmp_path / "heo-s90"
    make(set_dir, "heo", seed=90, burn_ms=0.5)
    row = check_set(set_dir, tmp_path / "fits")
    record = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())
    assert row.burn_ok or not record["converged"], row.burns


@pytest.mark.slow
@pytest.mark.parametrize("family, seed, burn_ms", [("heo", 150, 0.5), ("heo", 152, 1.0)])
def test_a_burn_fit_holds_the_truth_inside_its_covariance_after_the_burn(tmp_path, family, seed, burn_ms):
    """Both burns are measured (time within 2 sigma, size within 1). The state's covariance had
    taken the burn time's uncertainty by a derivative that held the pre-burn orbit and delta-v
    fixed; refitted with the burn moved, the fit moves both, and the truth after the burn had lain
    at Mahalanobis^2 120 and 27. The spread of those refits (tests/fit/test_burn_time_covariance.py)
    holds it."""
    row, set_dir = _burn_measured(tmp_path, family, seed, burn_ms)


@pytest.mark.slow
def test_a_right_burn_whose_fit_needs_more_than_thirty_iterations_is_kept(tmp_path):
    """heo seed 198 with a 1 m/s burn: the search's fit in the burn's gap lowered the cost by 41,384
    (weighted RMS 0.94) but stopped at 30 iterations not converged, the burn was not kept and the
    fit said no burn explains the arc. With BURN_ITERATIONS per pass it converges and the search
    keeps it. Its one night after the burn then decides: reported, its time and size within 3
    sigma and the truth inside the covariance, or not clean because its size is within 3 sigma of
    none (0.62 +- 0.31 m/s once moved fits keep the estimate's rejections) - never "no burn"."""
    set_dir = tmp_path / "heo-s198"
    make(set_dir, "heo", seed=198, burn_ms=1.0)
    row = check_set(set_dir, tmp_path / "fits")
    if not _measured_when_clean(row):
        record = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())
        assert any("the burn the search kept" in m for m in record["messages"]), record["messages"]


def _measured_when_clean(row) -> bool:
    """Whether the fit is clean; when it is, asserts one burn, its time and size within 3 sigma and
    the truth inside the orbit's covariance over the arc."""
    if row.outcome != "converged":
        return False
    assert row.burns.startswith("1:") and row.burn_ok, row.burns
    assert max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2
    return True



@pytest.mark.slow
def test_a_burn_the_ballistic_fit_absorbed_within_the_noise_is_found_by_the_screen_and_measured(tmp_path):
    """heo seed 270 with a 0.3 m/s burn in a six-day gap: the ballistic fit converged with weighted
    RMS 1.16, rejecting only the injected outliers, and was reported clean with the truth at
    Mahalanobis^2 4.6e6. A burn in that gap lowers the linearised cost by 72 (23.5 needed): it is
    searched and measured, 0.339 +- 0.17 m/s, time z +0.5."""
    _burn_measured(tmp_path, "heo", 270, 0.3)


@pytest.mark.slow
def test_a_burn_fit_under_auto_drops_an_area_to_mass_ratio_the_burn_leaves_insignificant(tmp_path):
    """nrho seed 1204 with a 0.5 m/s burn and no radiation pressure: the ballistic fit carried a
    ratio (absorbing the burn), the search estimated it with the burn, and the orbit was exported
    with -0.0055 +- 0.0022 m^2/kg, worded "estimated as asked (area_to_mass = 'solve')" under the
    default "auto". Refitted without it, the burn stays measured."""
    set_dir = tmp_path / "nrho-s1204"
    make(set_dir, "nrho", seed=1204, burn_ms=0.5)
    row = check_set(set_dir, tmp_path / "fits")
    assert _measured_when_clean(row), row.failure
    ratio = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["area_to_mass"]
    assert not ratio["estimated"] and ratio["decision"].startswith("not estimated: with the burns fitted"), ratio


@pytest.mark.slow
def test_a_ratio_kept_in_a_fit_that_is_not_clean_says_it_may_be_absorbing_a_maneuver(tmp_path):
    """nrho seed 1203 with a 1 m/s burn that no search explains: its ballistic fit's ratio, 0.54
    m^2/kg at 200 sigmas on a set with no radiation pressure, had been recorded as plainly estimated."""
    set_dir = tmp_path / "nrho-s1203"
    make(set_dir, "nrho", seed=1203, burn_ms=1.0)
    row = check_set(set_dir, tmp_path / "fits")
    ratio = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["area_to_mass"]
    if row.outcome == "converged" or not ratio["estimated"]:
        pytest.skip(f"the set is not a failed fit with a ratio any more ({row.outcome}, {ratio['decision']})")
    assert "in a fit that is not clean" in ratio["decision"], ratio


def _failed_fit_messages(set_dir: Path, tmp_path: Path) -> list[str]:
    """The messages of ``cistrack fit`` on ``set_dir``'s observations, a fit that must be failed."""
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "failed", row
    return json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["messages"]


@pytest.mark.slow
def test_a_site_given_a_wrong_code_is_named_beside_the_maneuver_it_looks_like(tmp_path):
    """nrho seed 1200, no burn, every observation of 711 labelled 568 (Maunakea): the fit is not
    clean and had been blamed only on "an object that maneuvered"; without 568's observations the
    others fit cleanly, and the note says so."""
    set_dir = tmp_path / "nrho-s1200"
    make(set_dir, "nrho", seed=1200)
    psv = set_dir / "observations.psv"
    psv.write_text(psv.read_text().replace("|711|", "|568|"))
    messages = _failed_fit_messages(set_dir, tmp_path)
    assert any("without site 568's" in m and "stated-uncertainty error at 568" in m for m in messages), messages


def _shifted(row: str, seconds: float) -> str:
    """An ADES PSV data row with its obsTime ``seconds`` later."""
    cells = row.split("|")
    t = datetime.fromisoformat(cells[3].strip().replace("Z", "+00:00")) + timedelta(seconds=seconds)
    cells[3] = t.strftime("%Y-%m-%dT%H:%M:%S.%fZ")
    return "|".join(cells)


def _late(psv: Path, site: str, seconds: float) -> None:
    """Rewrites the ADES PSV ``psv`` with every obsTime of ``site`` ``seconds`` later."""
    lines = psv.read_text().splitlines()
    psv.write_text("\n".join(lines[:2] + [_shifted(r, seconds) if r.split("|")[2] == site else r for r in lines[2:]]) + "\n")


@pytest.mark.slow
def test_a_clock_offset_at_the_site_with_most_observations_is_measured(tmp_path):
    """nrho seed 1301, no burn, every time of M22 (37 of 67 rows) 30 s late: the note blamed only "an
    object that maneuvered" (probe K1); the clock test measures the offset, and the fit with M22's
    times corrected by it is clean."""
    set_dir = tmp_path / "nrho-s1301"
    make(set_dir, "nrho", seed=1301)
    _late(set_dir / "observations.psv", "M22", 30.0)
    messages = _failed_fit_messages(set_dir, tmp_path)
    said = [m for m in messages if "site M22's times look" in m]
    assert said and " s late against the other sites'" in said[0] and "the fit is clean" in said[0], messages
    offset, sigma = (float(x) for x in re.search(r"look ([\d.]+) \+- ([\d.]+) s late", said[0]).groups())
    assert abs(offset - 30.0) <= 3.0 * sigma


@pytest.mark.slow
def test_a_site_filed_under_another_code_is_named_when_the_pulled_orbit_is_no_start(tmp_path):
    """heo seed 1300, no burn, 568's rows filed as 711: the ballistic fit sits at RMS 780, the other
    sites' fit from it does not converge, and no site had been named (probe K1); their own IOD fits
    them cleanly."""
    set_dir = tmp_path / "heo-s1300"
    make(set_dir, "heo", seed=1300)
    psv = set_dir / "observations.psv"
    psv.write_text(psv.read_text().replace("|568|", "|711|"))
    messages = _failed_fit_messages(set_dir, tmp_path)
    assert any("without site 711's" in m for m in messages), messages


@pytest.mark.slow
def test_a_burn_whose_nights_sit_off_whole_is_not_blamed_on_the_reject_cap(tmp_path):
    """nrho seed 1314 with a 3 m/s burn that no search explains: its first night sits 126 sigma off,
    two of its observations kept by the reject cap; the note had opened with "2 observations ... are
    kept because fit.max_reject_fraction ...; they may be what pulls the fit" (probe K5)."""
    set_dir = tmp_path / "nrho-s1314"
    make(set_dir, "nrho", seed=1314, burn_ms=3.0)
    row = check_set(set_dir, tmp_path / "fits")
    messages = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["messages"]
    if row.outcome == "converged":
        pytest.skip(f"the burn is measured now: {row.burns}")
    assert any(m.startswith("not a clean fit: it looks like an object that maneuvered") for m in messages), messages


@pytest.mark.slow
def test_a_burn_one_sites_ballistic_fit_absorbs_is_not_blamed_on_the_other_site(tmp_path):
    """dro seed 1318 with a 1 m/s burn: M22's 45 observations alone fit ballistically within the noise,
    and the fit that is not clean had blamed G96's lone tracklet ("a clock or position error at
    G96?"). A site is named only when two sites or more remain and the screen finds no burn in them."""
    set_dir = tmp_path / "dro-s1318"
    make(set_dir, "dro", seed=1318, burn_ms=1.0)
    check_set(set_dir, tmp_path / "fits")
    messages = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["messages"]
    assert not any("uncertainty error at" in m for m in messages), messages


@pytest.mark.slow
@pytest.mark.parametrize("family, seed", [("halo", 255), ("heo", 251)])
def test_a_burn_the_ballistic_start_cannot_reach_is_fitted_from_where_its_sides_meet(tmp_path, family, seed):
    """Both with a 1 m/s burn, both reported "not clean" before. halo seed 255: 13.7 days into a
    20-day arc whose first night is ten days before the rest, every full fit in the burn's gap from
    the ballistic orbit ran off (weighted RMS 5,695 at the true time). heo seed 251: a gross outlier
    the night before the burn pulled every fit's first pass along the delta-v's weak direction until
    that night (8 observations) was rejected, from the truth itself. Each side of the gap determines
    its orbit alone; started where they meet, the sides' outliers out of the first pass and every
    fit moved in time carrying the estimate's rejections, the burn is measured."""
    row, set_dir = _burn_measured(tmp_path, family, seed, 1.0)
    assert row.rejected_injected == row.injected


@pytest.mark.slow
def test_a_burn_with_two_nights_before_it_is_reported_with_the_size_it_can_give(tmp_path):
    """dro seed 252 with a 1 m/s burn after its second night: the fit with the burn drops the
    chi-square by 14,896 and fits every night (weighted RMS 0.86), but two nights leave one direction
    of the orbit before it weak and the size came out 0.86 +- 0.32 m/s, within 3 sigma of none: the
    fit had been called not clean and no orbit given. It is reported, with words on its size."""
    row, set_dir = _burn_measured(tmp_path, "dro", 252, 1.0)
    record = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())
    assert any("is within 3 sigma of none: the observations either side show a burn" in m for m in record["messages"])


def _burn_measured(tmp_path, family: str, seed: int, burn_ms: float):
    """(check row, set folder) of the survey set ``family`` ``seed`` with one burn of ``burn_ms``,
    fitted with no option; asserts it converged with one burn, its time and size within 3 sigma,
    and the truth inside the orbit's covariance over the arc."""
    set_dir = tmp_path / f"{family}-s{seed}"
    make(set_dir, family, seed=seed, burn_ms=burn_ms)
    row = check_set(set_dir, tmp_path / "fits")
    assert row.outcome == "converged", row.failure
    assert row.burns.startswith("1:") and row.burn_ok, row.burns
    assert max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2
    ratio = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["area_to_mass"]
    assert ratio is not None and ratio["decision"], ratio  # under "auto" the fit says what it did with the ratio
    return row, set_dir


@pytest.mark.slow
def test_burns_that_one_sites_clock_error_passes_for_are_not_reported(tmp_path):
    """dro seed 1512 with a 1 m/s burn and T08's times 20 s late (probe M1): the search fitted three
    burns, the real one and two about T08's first night (5 and 4 sigma), and the fit had been
    reported converged with all three, the truth 162 km from the exported orbit. With T08's offset
    fitted beside the burns those two no longer differ from none: the fit is not clean, T08 named."""
    set_dir = tmp_path / "dro-s1512"
    make(set_dir, "dro", seed=1512, burn_ms=1.0)
    _late(set_dir / "observations.psv", "T08", 20.0)
    messages = _failed_fit_messages(set_dir, tmp_path)
    assert any("a clock or position error at T08" in m for m in messages), messages


@pytest.mark.slow
def test_a_site_offset_the_fit_keeps_is_worded_clock_or_position_and_widens_its_covariance(tmp_path):
    """dro seed 1504 with G96's rows filed as 703, 6 km away (probe M2): read as 703's times 6.2 s
    early, the fit was kept "well determined" with the truth at Mahalanobis^2 56. The words offer a
    position error too, and the kept fit's covariance carries the offset as a consider parameter,
    the truth inside it over the arc."""
    set_dir = tmp_path / "dro-s1504"
    make(set_dir, "dro", seed=1504)
    psv = set_dir / "observations.psv"
    psv.write_text(psv.read_text().replace("|G96|", "|703|"))
    row = check_set(set_dir, tmp_path / "fits")
    messages = json.loads((tmp_path / "fits" / set_dir.name / "fit.json").read_text())["messages"]
    assert any("a clock or position error at 703" in m and "covariance widened" in m for m in messages), messages
    assert row.outcome == "converged" and max(row.m2) <= MAHALANOBIS2_BOUND, row.max_m2


@pytest.mark.slow
def test_two_sites_with_clocks_off_are_both_measured(tmp_path):
    """dro seed 1504 with J04's times 45 s late and G96's 20 s early (probe M5): J04 alone had been
    named, 54.5 s late, and the fit with it corrected called clean at weighted RMS 1.45 over 49
    observations. Tested again after J04's correction, G96 is named too, both offsets measured."""
    set_dir = tmp_path / "dro-s1504"
    make(set_dir, "dro", seed=1504)
    _late(set_dir / "observations.psv", "J04", 45.0)
    _late(set_dir / "observations.psv", "G96", -20.0)
    messages = _failed_fit_messages(set_dir, tmp_path)
    said = [m for m in messages if "site J04's times look" in m]
    assert said and "site G96's" in said[0], messages
    late, early = (float(x) for x in re.search(r"J04's times look ([\d.]+) \+- [\d.]+ s late and site G96's ([\d.]+) "
                                               r"\+- [\d.]+ s early", said[0]).groups())
    assert abs(late - 45.0) <= 5.0 and abs(early - 20.0) <= 5.0, said[0]


@pytest.mark.slow
def test_a_site_the_leave_out_could_not_test_is_named_beside_the_one_it_did(tmp_path):
    """dro seed 1501 with W68's rows filed as X03, 7.6 km away (probe M3): X03 could not be left out
    (the others do not span 90 % of the arc) and 809, the one site tested and the one right, had
    been named alone. The words name X03 beside it."""
    set_dir = tmp_path / "dro-s1501"
    make(set_dir, "dro", seed=1501)
    psv = set_dir / "observations.psv"
    psv.write_text(psv.read_text().replace("|W68|", "|X03|"))
    said = [m for m in _failed_fit_messages(set_dir, tmp_path) if "stated-uncertainty error at" in m]
    assert said and all("X03" in m.split("stated-uncertainty error at")[1] for m in said), said
