"""The regularised particle filter (``rpf``): a particle baseline that approaches the exact
Kalman posterior on a linear-Gaussian problem and survives arcsecond measurements where the
bootstrap filter's weights degenerate."""
from __future__ import annotations

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.plugins.filters.regularized_sir import RegularizedSIRFilter, kernel_bandwidth
from cistrack.plugins.filters.sir import SIRFilter

from cistrack.model.measurement import Measurement

from .linear_models import LinearDynamics, LinearSensor
from .test_linear_gaussian import assert_matches_kalman, problem, run_filter  # noqa: F401  (fixture)


def test_silverman_bandwidth_in_one_dimension_is_the_textbook_1_06_n_to_the_minus_one_fifth():
    # Silverman (1986), eq. 3.28: h = 1.06 sigma n^(-1/5) for a Gaussian kernel in one dimension
    for n in (100, 10000):
        assert kernel_bandwidth(n, "silverman", dim=1) == pytest.approx(1.06 * n ** -0.2, rel=2e-3)


def test_scott_bandwidth_is_n_to_the_minus_one_over_d_plus_4():
    assert kernel_bandwidth(10000, "scott") == pytest.approx(10000 ** (-1 / 10))


def test_regularised_filter_approaches_the_exact_kalman_posterior_on_a_linear_problem(problem):  # noqa: F811
    *_, m, P = problem
    filt = RegularizedSIRFilter(n_particles=20000)
    belief = run_filter(filt, problem)
    assert_matches_kalman(belief, m, P, mean_tol=0.15, cov_tol=0.08)


def test_regularised_filter_keeps_its_particles_distinct_where_the_bootstrap_filter_depletes(problem):  # noqa: F811
    rpf, sir = RegularizedSIRFilter(n_particles=5000), SIRFilter(n_particles=5000)
    run_filter(rpf, problem)
    run_filter(sir, problem)
    assert rpf.diagnostics["unique_particles"] == 5000
    assert sir.diagnostics["unique_particles"] < 0.5 * 5000


def test_each_tempering_stage_keeps_the_effective_sample_size_at_its_target(problem):  # noqa: F811
    _, ms, cloud, _, _ = problem
    sharp = LinearSensor(sigma=0.002, coords=(0, 1, 2))      # a likelihood ~350x narrower than the prior
    filt = RegularizedSIRFilter(n_particles=4000, ess_target=0.5)
    filt.initialize(cloud, LinearDynamics(), sharp, np.random.default_rng(1))
    m = ms[0]
    filt.predict(m.t)
    filt.update(Measurement(m.t, m.z, np.eye(3) * 0.002 ** 2, sharp.names))
    assert filt.diagnostics["stages"] > 3
    assert filt.diagnostics["ess_before_resampling"] >= 0.5 * 4000 * (1 - 1e-6)


def test_a_bandwidth_that_cannot_be_shrunk_is_refused_naming_the_parameter():
    with pytest.raises(ParameterError, match="bandwidth_scale"):
        RegularizedSIRFilter(n_particles=100, bandwidth_scale=5.0)
