"""Re-anchoring (plugins/filters/pgm/reanchoring.py): when it is due, and what it returns.

Two nights of az/el measurements of the 9:2 NRHO from the ground (1.5 arcsec, every 40 minutes
while visible), ten days apart, simulated with the real ``ground-telescope`` and ``cr3bp``
components; the posterior particles stand for a wide but honest filter belief at the end of the
second night (truth plus a Gaussian spread of about 300 km and 3 m/s)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

from cistrack.errors import ParameterError
from cistrack.model.measurement import Measurement
from cistrack.plugin.registry import default_registry
from cistrack.plugins.filters.pgm.reanchoring import Reanchoring
from cistrack.plugins.filters.pgm import PaperPGMFilter, PGMFilter
from cistrack.units import days_to_tu, hours_to_tu, km_to_lu, kms_to_vu

NRHO = np.array([1.0221, 0.0, -0.1821, 0.0, -0.1033, 0.0])
MAHALANOBIS2_99 = 16.81  # chi-square(6) at 99 %


@lru_cache(maxsize=1)
def _two_nights():
    reg = default_registry()
    dyn = reg.create("dynamics", "cr3bp")
    sen = reg.create("sensor", "ground-telescope", epoch="2026-01-01T00:00:00Z")
    step = float(hours_to_tu(40.0 / 60.0))
    grid = np.concatenate([np.arange(1, 37) * step, days_to_tu(10.0) + np.arange(1, 37) * step])
    seen = sen.visible(dyn.propagate(NRHO[None], 0.0, grid).states[:, 0], grid)
    times = grid[seen]
    truth = dyn.propagate(NRHO[None], 0.0, times).states[:, 0]
    z = sen.measure(truth, times)
    sig = sen.sigmas(truth, times)
    return dyn, sen, times, truth, z, sig


def _measurements(seed: int, bias_arcsec: float = 0.0) -> list[Measurement]:
    _, sen, times, _, z, sig = _two_nights()
    rng = np.random.default_rng(seed)
    noisy = z + rng.standard_normal(z.shape) * sig
    late = times > days_to_tu(5.0)
    noisy[late] += np.deg2rad(bias_arcsec / 3600.0)
    return [Measurement(float(t), noisy[k], np.diag(sig[k] ** 2), tuple(sen.names), k)
            for k, t in enumerate(times)]


def _particles(seed: int, n: int = 400) -> np.ndarray:
    _, _, _, truth, _, _ = _two_nights()
    spread = np.concatenate([np.full(3, km_to_lu(300.0)), np.full(3, kms_to_vu(3e-3))])
    return truth[-1] + np.random.default_rng(seed).standard_normal((n, 6)) * spread


def _observed(reanchor: Reanchoring, ms: list[Measurement]) -> Reanchoring:
    for m in ms:
        reanchor.observe(m)
    return reanchor


def test_the_two_nights_are_ten_days_apart_and_each_has_a_pass():
    _, _, times, _, _, _ = _two_nights()
    late = times > days_to_tu(5.0)
    assert 6 <= np.count_nonzero(~late) and 6 <= np.count_nonzero(late)


def test_nothing_is_due_while_a_pass_goes_on():
    ms = _measurements(1)
    early = [m for m in ms if m.t < days_to_tu(5.0)]
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 8), early)
    assert not r.due(early[-1].t + hours_to_tu(1.0))


def test_an_attempt_is_due_once_the_post_gap_pass_pauses():
    ms = _measurements(1)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms)
    assert not r.due(ms[-1].t + hours_to_tu(1.0))
    assert r.due(ms[-1].t + hours_to_tu(3.5))


def test_an_arc_starts_afresh_after_a_gap():
    ms = _measurements(1)
    n_late = sum(m.t > days_to_tu(5.0) for m in ms)
    r = _observed(Reanchoring("arcs", 5.0, 3.0, n_late + 1, 8), ms)
    assert len(r.history) == n_late
    assert not r.due(ms[-1].t + days_to_tu(1.0))


def test_across_gaps_the_arc_keeps_every_measurement():
    ms = _measurements(1)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms)
    assert len(r.history) == len(ms)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_solution_holds_the_truth_inside_its_covariance(seed):
    dyn, sen, _, truth, _, _ = _two_nights()
    ms = _measurements(seed)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms)
    mix = r.attempt(_particles(seed), ms[-1].t, dyn, sen)
    assert mix is not None
    e = truth[-1] - mix.mean
    assert e @ np.linalg.solve(mix.covariance, e) < MAHALANOBIS2_99


def test_after_a_gap_the_solution_is_its_line_of_variations():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(1)
    mix = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms).attempt(_particles(1), ms[-1].t, dyn, sen)
    assert mix.n_components >= 9  # the nominal point and at least 4 on each side, half a sigma apart
    assert np.argmax(mix.weights) == mix.n_components // 2  # the nominal solution weighs most


def test_within_an_arc_the_solution_is_one_gaussian_per_minimum():
    dyn, sen, _, _, _, _ = _two_nights()
    early = [m for m in _measurements(7) if m.t < days_to_tu(5.0)]
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 2), early)
    mix = r.attempt(_particles(7)[:50], early[-1].t, dyn, sen)
    assert mix is None or mix.n_components == r.solutions


def test_the_solution_is_far_sharper_than_the_particles_it_started_from():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(4)
    x = _particles(4)
    mix = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms).attempt(x, ms[-1].t, dyn, sen)
    sigma_fit = np.sqrt(np.trace(mix.covariances[0][:3, :3]))
    sigma_cloud = np.sqrt(np.trace(np.cov(x[:, :3].T)))
    assert sigma_fit < 0.1 * sigma_cloud


def test_measurements_no_orbit_fits_leave_the_belief_alone():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(5, bias_arcsec=60.0)  # the second night displaced by one arcminute
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 4), ms)
    assert r.attempt(_particles(5), ms[-1].t, dyn, sen) is None


def test_no_second_attempt_without_new_measurements():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(6)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 2), ms)
    r.attempt(_particles(6), ms[-1].t, dyn, sen)
    assert not r.due(ms[-1].t + days_to_tu(1.0))


def test_pgm_refuses_a_negative_gap_naming_the_parameter():
    with pytest.raises(ParameterError, match="reanchor_gap_days"):
        PGMFilter(reanchor_gap_days=-1.0)


def test_pgm_refuses_an_unknown_mode_naming_the_choices():
    with pytest.raises(ParameterError, match="across-gaps"):
        PGMFilter(reanchor="sometimes")


def test_pgm_re_anchors_arcs_by_default_and_the_paper_pgm_does_not():
    assert PGMFilter().reanchor == "arcs"
    assert PaperPGMFilter().reanchor == "off"


def test_arcs_mode_is_due_at_the_end_of_each_pass_with_new_measurements():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(7)
    early = [m for m in ms if m.t < days_to_tu(5.0)]
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 2), early)
    assert r.due(early[-1].t + hours_to_tu(3.5))


def test_arcs_mode_waits_for_new_measurements_after_an_attempt():
    dyn, sen, _, _, _, _ = _two_nights()
    ms = _measurements(7)
    early = [m for m in ms if m.t < days_to_tu(5.0)]
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 2), early[:-1])
    r.attempt(_particles(7)[:50], early[-2].t, dyn, sen)
    assert not r.due(early[-2].t + days_to_tu(1.0))
    r.observe(early[-1])
    assert r.due(early[-1].t + hours_to_tu(3.5))


def test_a_single_pass_is_never_fitted_on_its_own():
    ms = _measurements(8)
    first_pass = [m for m in ms if m.t < hours_to_tu(10.0)]  # 6 measurements in the first 4 hours
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 8), first_pass)
    assert len(r.history) >= 6
    assert not r.due(first_pass[-1].t + days_to_tu(1.0))


def test_after_a_gap_an_arc_waits_for_its_second_pass():
    ms = _measurements(8)
    late = [m for m in ms if m.t > days_to_tu(5.0)]  # one 10-hour pass after the gap
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 8), ms)
    assert len(r.history) == len(late)
    assert not r.due(ms[-1].t + days_to_tu(1.0))


def test_after_a_gap_the_particles_are_drawn_along_the_line():
    dyn, sen, _, truth, _, _ = _two_nights()
    ms = _measurements(2)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms)
    mix = r.attempt(_particles(2), ms[-1].t, dyn, sen)
    x = r.draw(3000, np.random.default_rng(0))
    assert x.shape == (3000, 6)
    e = truth[-1] - x.mean(axis=0)
    assert e @ np.linalg.solve(np.cov(x.T), e) < MAHALANOBIS2_99
    np.testing.assert_allclose(x.mean(axis=0), mix.mean, atol=3 * np.sqrt(np.diag(mix.covariance)).max() / np.sqrt(3000))


def test_within_an_arc_the_particles_come_from_the_mixture():
    dyn, sen, _, _, _, _ = _two_nights()
    early = [m for m in _measurements(7) if m.t < days_to_tu(5.0)]
    r = _observed(Reanchoring("arcs", 5.0, 3.0, 6, 2), early)
    r.attempt(_particles(7)[:50], early[-1].t, dyn, sen)
    assert r.draw(100, np.random.default_rng(0)) is None


def test_pgm_refuses_a_kernel_threshold_outside_0_1_naming_it():
    with pytest.raises(ParameterError, match="kernel_ess"):
        PGMFilter(kernel_ess=1.5)


def test_continued_fits_across_the_gap_reach_the_direct_fits_solution():
    from cistrack.least_squares import FitOptions
    from cistrack.plugins.filters.pgm.reanchoring import _DifferencedDynamics

    dyn, sen, _, truth, _, _ = _two_nights()
    ms = _measurements(3)
    r = _observed(Reanchoring("across-gaps", 5.0, 3.0, 6, 8), ms)
    r.attempt(_particles(3), ms[-1].t, dyn, sen)
    nominal = next(p.state for p in r._valleys[1][0][0] if p.sigma == 0.0)
    x = _particles(3, n=4)
    opts = FitOptions(reject_outliers=False, max_iterations=300, max_damping=1e12)
    kept = r._continued_fits(np.arange(4), x, ms[-1].t, r._measurement_set(), _DifferencedDynamics(dyn, 1e-8),
                             sen, opts, 1e9)
    assert len(kept) == 1
    e = kept[0].state - nominal
    assert e @ np.linalg.solve(kept[0].covariance, e) < 1e-2  # the same minimum
