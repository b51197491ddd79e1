"""NIS: measurements drawn from the prior are chi-square(m) distributed under it."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.model.belief import Belief, GaussianMixture, ParticleCloud
from cistrack.evaluation.consistency import innovation_nis, nis_test
from cistrack.model.measurement import Measurement
from cistrack.plugin.registry import default_registry


def test_nis_of_measurements_drawn_from_the_prior_averages_the_dimension(nrho_arc):
    times, states = nrho_arc
    sensor = default_registry().create("sensor", "ground-telescope", sigma_arcsec=1.5)
    k = int(np.argmax(sensor.visible(states, times)))
    t, x0 = times[k], states[k]
    rng = np.random.default_rng(1)
    cov = np.diag([1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4]) ** 2 * 1e4     # ~40 km, ~10 m/s
    samples = rng.multivariate_normal(x0, cov, size=4000)
    prior = Belief(t, GaussianMixture(np.ones(1), x0[None], cov[None]), ParticleCloud(samples, t))
    nis = []
    for _ in range(300):
        xt = rng.multivariate_normal(x0, cov)
        s = sensor.sigmas(xt[None], t)[0]
        z = sensor.measure(xt[None], t)[0] + rng.standard_normal(2) * s
        nis.append(innovation_nis(prior, Measurement(t, z, np.diag(s ** 2), sensor.names), sensor)[0])
    res = nis_test(nis, 2, level=0.99)
    assert res.within, res
    assert res.mean == pytest.approx(2.0, abs=0.45)


def test_nis_test_bounds_are_the_chi_square_quantiles_of_the_mean():
    from scipy.stats import chi2
    r = nis_test(np.full(50, 2.0), 2, level=0.95)
    assert r.lower == pytest.approx(chi2.ppf(0.025, 100) / 50) and r.upper == pytest.approx(chi2.ppf(0.975, 100) / 50)
    assert r.within and not nis_test(np.full(50, 4.0), 2).within


def test_updates_of_different_sizes_are_tested_with_the_summed_degrees_of_freedom():
    from scipy.stats import chi2
    rng = np.random.default_rng(1)
    dof = np.array([2, 4] * 200)
    r = nis_test(rng.chisquare(dof), dof, level=0.95)
    assert r.dof == pytest.approx(3.0) and r.n == 400
    assert r.lower == pytest.approx(chi2.ppf(0.025, 1200) / 400) and r.upper == pytest.approx(chi2.ppf(0.975, 1200) / 400)
    assert r.within and not nis_test(rng.chisquare(dof) * 1.5, dof).within
