"""The conformance suite names the failing check and says why; its entry points behave."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cistrack.interfaces.component import check_int
from cistrack.errors import ParameterError, UnknownComponentError
from cistrack.plugin.hookspecs import hookimpl
from cistrack.interfaces import Clusterer, Propagation, ReferenceOrbit
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import Registry
from cistrack.testing import (CheckResult, ConformanceError, GeocentricAnglesSensor, ReferenceCR3BP,
                              check_plugin, check_registered, iter_checks, parametrize_with_checks)
from cistrack.testing.reference_dynamics import cr3bp_derivatives
from cistrack.units import ARCSEC_RAD


class HalvesClusterer(Clusterer):
    """Splits on the sign of the leading principal component of the standardised particles
    (a correct, tiny clusterer)."""

    def __init__(self, n_components: int = 2):
        self.n_components = check_int(self, "n_components", n_components, minimum=1)

    def cluster(self, x, rng):
        x = np.asarray(x, dtype=float)
        z = (x - x.mean(axis=0)) / x.std(axis=0)
        return (z @ np.linalg.svd(z, full_matrices=False)[2][0] > 0).astype(np.intp)


class InPlaceClusterer(HalvesClusterer):
    """Standardises the caller's array in place."""

    def cluster(self, x, rng):
        x -= x.mean(axis=0)
        x /= x.std(axis=0)
        return (x @ np.linalg.svd(x, full_matrices=False)[2][0] > 0).astype(np.intp)


class UncheckedClusterer(HalvesClusterer):
    """Stores a float parameter without validating it."""

    def __init__(self, n_components: int = 2, spread: float = 1.0):
        super().__init__(n_components)
        self.spread = spread


class GlobalRandomClusterer(HalvesClusterer):
    """Draws from numpy's global generator instead of the one it is given."""

    def cluster(self, x, rng):
        np.random.random()
        return super().cluster(x, rng)


class ArcsecSigmasSensor(GeocentricAnglesSensor):
    """Simulates angles in radians but writes their sigmas in arcsec."""

    def simulate(self, states, times, rng):
        ms = super().simulate(states, times, rng)
        return MeasurementSet(ms.times, ms.values, ms.sigmas / ARCSEC_RAD, ms.names)


def _failure(component, check_name):
    with pytest.raises(ConformanceError) as info:
        check_plugin(component)
    failed = {r.name: r.message for r in info.value.results if not r.passed}
    assert check_name in failed, f"expected {check_name} to fail; failures: {failed}"
    return str(info.value), failed[check_name]


def test_a_correct_component_passes_and_gets_a_report():
    report = check_plugin(HalvesClusterer)
    assert report.passed and {r.name for r in report.results} >= {"separates_two_blobs", "picklable"}


def test_the_reference_fixtures_pass_their_own_suite():
    assert check_plugin(ReferenceCR3BP).passed
    assert check_plugin(GeocentricAnglesSensor(range_fraction=0.1)).passed


def test_modifying_an_input_in_place_is_reported_by_check_and_input_name():
    message, why = _failure(InPlaceClusterer, "reproducible")
    assert "check 'reproducible' failed for clustering 'InPlaceClusterer'" in message
    assert "input 'x' was modified in place" in why


def test_an_unvalidated_parameter_is_reported_with_its_name():
    _, why = _failure(UncheckedClusterer, "bad_parameters_raise_parameter_error")
    assert "spread" in why and "was accepted" in why


def test_global_random_state_is_reported():
    _, why = _failure(GlobalRandomClusterer, "reproducible")
    assert "global random state" in why


def test_noise_in_the_wrong_units_is_reported():
    _, why = _failure(ArcsecSigmasSensor, "simulate_noise_matches_sigmas")
    assert "RMS" in why and "units" in why


def test_a_component_that_cannot_be_built_with_defaults_fails_construction():
    class NeedsPath(HalvesClusterer):
        def __init__(self, n_components: int = 2, path: str | None = None):
            super().__init__(n_components)
            if path is None:
                raise ParameterError("clustering 'NeedsPath': parameter 'path' is required")
            self.path = path

    _, why = _failure(NeedsPath, "constructs_with_defaults")
    assert "parameter 'path' is required" in why


def test_iter_checks_yields_named_callables_that_raise_conformance_error():
    checks = dict(iter_checks(InPlaceClusterer))
    assert "separates_two_blobs" in checks
    checks["separates_two_blobs"]()
    with pytest.raises(ConformanceError, match="reproducible"):
        checks["reproducible"]()


def test_conformance_error_is_an_assertion_error():
    assert issubclass(ConformanceError, AssertionError)


def _registry() -> Registry:
    reg = Registry()
    reg.add("clustering", "halves", HalvesClusterer)
    reg.add("clustering", "in-place", InPlaceClusterer)
    reg.add("dynamics", "halves", ReferenceCR3BP)
    return reg


def test_check_registered_returns_results_without_raising():
    results = check_registered("in-place", registry=_registry())
    assert all(isinstance(r, CheckResult) for r in results)
    assert [r.name for r in results if not r.passed] == ["reproducible"]


def test_check_registered_needs_a_kind_for_a_name_used_by_two_kinds():
    with pytest.raises(ParameterError, match="clustering, dynamics|dynamics, clustering"):
        check_registered("halves", registry=_registry())
    assert all(r.passed for r in check_registered("halves", kind="clustering", registry=_registry()))


def test_check_registered_names_the_known_components_for_an_unknown_name():
    with pytest.raises(UnknownComponentError, match="in-place"):
        check_registered("no-such-thing", registry=_registry())


@parametrize_with_checks([HalvesClusterer, HalvesClusterer(n_components=3)])
def test_parametrize_with_checks_runs_each_check_as_a_test(component, check):
    check(component)


class StackedCR3BP(ReferenceCR3BP):
    """Propagates all particles as one stacked solve_ivp system (one error norm for all)."""

    def propagate(self, states, t0, times):
        x = np.asarray(states, dtype=float)
        n = x.shape[0]
        ts = np.atleast_1d(np.asarray(times, dtype=float))
        sol = solve_ivp(lambda t, y: cr3bp_derivatives(y.reshape(n, 6), self.mu).ravel(), (t0, ts[-1]), x.ravel(),
                        t_eval=ts, rtol=1e-9, atol=1e-12)
        return Propagation(ts, sol.y.T.reshape(len(ts), n, 6), np.ones(n, bool), np.full(n, -1), np.full(n, np.inf))


def test_a_stacked_integrator_fails_the_vectorised_equals_loop_check():
    _, why = _failure(StackedCR3BP, "propagate_vectorised_matches_loop")
    assert "one at a time" in why


def test_a_periodic_orbit_that_does_not_close_is_reported():
    good = ReferenceOrbit("l2-lyapunov", np.array([1.1257, 0, 0, 0, 0.1508, 0]), 3.404, 1.2150582e-2, "approximate")
    _, why = _failure(good, "periodic_orbit_closes")
    assert "misses its initial state" in why


def test_a_misspelt_recorder_hook_is_reported():
    class Recorder:
        @hookimpl
        def cistrack_step_update(self, run, step):  # should be cistrack_step_updated
            pass

    _, why = _failure(Recorder(), "implements_lifecycle_hooks")
    assert "cistrack_step_update" in why


class ExitingClusterer(HalvesClusterer):
    """Calls sys.exit(7) from cluster()."""

    def cluster(self, x, rng):
        raise SystemExit(7)


def test_a_component_calling_sys_exit_fails_each_check_that_calls_it_and_the_suite_goes_on():
    """The suite had ended with the plugin's exit status, without a FAIL line or a summary."""
    results = check_registered("exiting", registry=_registry_with(ExitingClusterer))
    failed = [r for r in results if not r.passed]
    assert failed and all("it raised SystemExit: it called sys.exit(7)" in r.message for r in failed)
    assert len(results) == len(list(iter_checks(ExitingClusterer, "clustering")))  # every check ran


class GeneratorExitClusterer(HalvesClusterer):
    """Raises GeneratorExit (a BaseException a generator helper can leak) from cluster()."""

    def cluster(self, x, rng):
        raise GeneratorExit()


def test_a_component_raising_generator_exit_fails_each_check_that_calls_it_and_the_suite_goes_on():
    """The suite had ended in a traceback, without a FAIL line or a summary (probe I1)."""
    results = check_registered("exiting", registry=_registry_with(GeneratorExitClusterer))
    failed = [r for r in results if not r.passed]
    assert failed and all(r.message.endswith("it raised GeneratorExit") for r in failed)
    assert len(results) == len(list(iter_checks(GeneratorExitClusterer, "clustering")))


def _registry_with(cls) -> Registry:
    reg = Registry()
    reg.add("clustering", "exiting", cls)
    return reg
