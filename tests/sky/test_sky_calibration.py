"""Are the sky ellipses of `cistrack predict` honest? Over simulated campaigns (the 9:2 NRHO of the
built-in ``real-data`` scenario in the ephemeris model, observed from MPC 711 and 809 with 1.0"
noise, the ``paper-example-1`` schedule), the orbit is fitted by least squares to the first three
days and predicted at the observation times of the following three; the truth's RA/Dec should lie
inside the predicted 3-sigma ellipse (Mahalanobis^2 <= 9) 98.9 % of the time, and its
Mahalanobis^2 average 2 (chi-square, 2 degrees of freedom).

Run ``.venv/bin/python tests/sky/test_sky_calibration.py`` for the table of every seed.
"""
import math

import numpy as np
import pytest

from cistrack import units
from cistrack.astro.site_network import build_site_network
from cistrack.astro.site_simulation import simulate_sites
from cistrack.astro.sites import observatory
from cistrack.fitting.sky_ephemeris import sky_ephemeris
from cistrack.least_squares import fit_orbit
from cistrack.plugin.registry import default_registry
from cistrack.scenario.loading import load_scenario

SEEDS = tuple(range(4900, 4925))
SITES = ("711", "809")
FIT_DAYS = 3.0


def campaign_m2(seed: int) -> np.ndarray:
    """The truth's Mahalanobis^2 under the predicted sky ellipse at every observation time after
    the fitted arc of campaign ``seed``, (J,)."""
    reg = default_registry()
    scen = load_scenario("real-data").with_overrides({"duration_days": 2 * FIT_DAYS})
    camp = simulate_sites(scen, {c: observatory(c) for c in SITES}, seed=seed)
    ms = camp.measurements
    early = ms.times < units.days_to_tu(FIT_DAYS)
    arc = ms.subset(early)
    dyn = scen.build("dynamics", reg)
    t0 = float(arc.times[-1])
    rng = np.random.default_rng(seed)
    start = camp.truth_at([t0])[0] + rng.normal(0.0, 1.0, 6) * np.r_[[1.0 / units.LU_KM] * 3, [1e-5 / units.VU_KMS] * 3]
    fit = fit_orbit(dyn, build_site_network(scen.components["sensor"], reg, arc), arc, start, t0)
    assert fit.converged
    cov = fit.covariance * max(1.0, fit.noise_scale) ** 2          # as `cistrack export` and `predict` do
    later = ms.subset(~early)
    out = []
    for code in SITES:
        times = later.times[np.asarray(later.sites) == code]
        if times.size == 0:
            continue
        sky = sky_ephemeris(dyn, fit.state, cov, t0, times, observatory(code), scen.epoch, reg)
        truth = _truth_radec(scen, reg, code, camp.truth_at(times), times)
        out.append(sky.mahalanobis2(*truth))
    return np.concatenate(out)


def _truth_radec(scen, reg, code, states, times):
    site = observatory(code)
    radec = reg.create("sensor", "real-telescope", measurement="radec", latitude_deg=site.latitude_deg,
                       longitude_deg=site.longitude_deg, height_m=site.height_m, epoch=units.format_utc(scen.epoch))
    z = radec.measure(states, times)
    return np.degrees(z[:, 0]), np.degrees(z[:, 1])


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion k/n."""
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


@pytest.mark.slow
def test_the_truth_falls_inside_the_3_sigma_sky_ellipse_at_the_expected_rate():
    """One orbit error per campaign moves all its predictions together (their Mahalanobis^2 differ
    by tens of percent at most), so each campaign is one trial: its first predicted time."""
    from scipy.stats import chi2, kstest

    first = np.array([campaign_m2(s)[0] for s in SEEDS])
    inside = int(np.sum(first <= 9.0))
    lo, hi = wilson(inside, first.size)
    assert lo <= 0.989 <= hi, (inside, first.size)
    assert kstest(first, chi2(2).cdf).pvalue > 0.01
    assert 1.0 < np.mean(first) < 3.0                                     # 2 +- 0.4 (standard error) for 25


if __name__ == "__main__":
    import sys

    from scipy.stats import chi2, kstest

    rows = []
    for s in (range(int(sys.argv[1]), int(sys.argv[2])) if len(sys.argv) > 2 else SEEDS):
        m = campaign_m2(s)
        rows.append(m)
        print(f"seed {s}: {m.size} times, inside 3-sigma {np.sum(m <= 9.0)}, mean M2 {np.mean(m):.2f}, "
              f"max {np.max(m):.2f}", flush=True)
    every = np.concatenate(rows)
    k = int(np.sum(every <= 9.0))
    lo, hi = wilson(k, every.size)
    print(f"all: {k} of {every.size} inside ({100 * k / every.size:.1f} %, Wilson 95 % {100 * lo:.1f}-{100 * hi:.1f} %); "
          f"mean M2 {np.mean(every):.2f}; seeds with every time inside: {sum(np.all(m <= 9.0) for m in rows)} of {len(rows)}")
    first = np.array([m[0] for m in rows])
    k = int(np.sum(first <= 9.0))
    lo, hi = wilson(k, first.size)
    print(f"first predicted time per seed: {k} of {first.size} inside (Wilson 95 % {100 * lo:.1f}-{100 * hi:.1f} %), "
          f"mean M2 {np.mean(first):.2f} +- {np.std(first, ddof=1) / np.sqrt(first.size):.2f}, "
          f"KS p against chi-square(2) {kstest(first, chi2(2).cdf).pvalue:.3f}")
