"""The PGM is composed of registered steps (issue 48): each step a component of its own kind,
listed by `cistrack plugins`, chosen by name in a scenario (a third party's too), and the
paper's PGM a preset of settings."""
from __future__ import annotations

import pickle

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.errors import ParameterError
from cistrack.interfaces import ComponentUpdate, KINDS, KernelUpdate, ParticlePrediction, PosteriorDraw, Reanchor
from cistrack.interfaces.preset import preset, preset_defaults
from cistrack.model.belief import ParticleCloud
from cistrack.plugin.param_docs import param_docs
from cistrack.plugin.registry import load_registry
from cistrack.plugins.filters.pgm import (AcrossGapsReanchor, AfterGapKernels, EnsembleUpdate, GaussianDraw,
                                          IteratedUpdate, NoKernels, NoReanchor, PaperPGMFilter, PGMFilter,
                                          PropagateParticles, TransformDraw)
from cistrack.plugins.filters.pgm.component_update import ensemble_component_update
from cistrack.scenario.loading import load_scenario

from .linear_models import LinearDynamics, LinearSensor, transition

STEPS = {"pgm-prediction": ["propagate"], "pgm-update": ["ensemble", "iterated"], "pgm-draw": ["gaussian", "transform"],
         "pgm-kernel": ["after-gap", "off"], "pgm-reanchor": ["across-gaps", "arcs", "off"]}


class CountingUpdate(ComponentUpdate):
    """A third party's component update: the paper's ensemble update, counting its calls."""

    uses_particles = True
    calls = 0

    def update(self, moments, residuals, R):
        CountingUpdate.calls += 1
        return ensemble_component_update(moments, R)


@pytest.fixture(scope="module")
def reg():
    r = load_registry(autoload_third_party=False)
    r.add("pgm-update", "test-counting", CountingUpdate)
    return r


def _linear_run(filt, seed: int = 7):
    """The filter's belief after three updates of a linear problem (free motion, x y z measured)."""
    rng = np.random.default_rng(42)
    sensor = LinearSensor(sigma=0.2, coords=(0, 1, 2))
    m0, p0 = np.array([1.0, 2.0, -0.5, 0.1, -0.1, 0.05]), np.diag([0.5, 0.5, 0.5, 0.05, 0.05, 0.05])
    times = np.array([0.5, 1.0, 1.5])
    ms = sensor.simulate(np.stack([transition(t) @ m0 for t in times]), times, rng)
    filt.initialize(ParticleCloud(rng.multivariate_normal(m0, p0, 3000), 0.0), LinearDynamics(), sensor,
                    np.random.default_rng(seed))
    for meas in ms:
        filt.predict(meas.t)
        filt.update(meas)
    return filt.belief


def test_each_step_is_a_registry_kind_with_its_builtin_names(reg):
    for kind, names in STEPS.items():
        assert kind in KINDS
        assert set(names) <= set(reg.names(kind))


def test_cistrack_plugins_lists_the_pgms_steps(capsys):
    assert main(["plugins"]) == 0
    out = capsys.readouterr().out
    for kind, names in STEPS.items():
        assert f"{kind} (" in out
        assert all(f"  {n} " in out for n in names)


def test_cistrack_plugins_kind_lists_one_step(capsys):
    assert main(["plugins", "--kind", "pgm-draw"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("pgm-draw (2)") and "transform" in out and "iterated" not in out


def test_the_old_mode_strings_of_a_scenario_build_the_named_steps(reg):
    scen = load_scenario("quick", reg, overrides={"filter": {"component_update": "ensemble",
                                                             "posterior_draw": "gaussian", "reanchor": "off"}})
    spec = scen.components["filter"].params["component_update"]
    assert (spec.kind, spec.name) == ("pgm-update", "ensemble")
    pgm = scen.build("filter", reg)
    assert isinstance(pgm.component_update, EnsembleUpdate)
    assert isinstance(pgm.posterior_draw, GaussianDraw)
    assert isinstance(pgm.reanchor, NoReanchor)


def test_a_scenario_left_at_the_defaults_builds_the_default_steps(reg):
    pgm = load_scenario("quick", reg).build("filter", reg)
    assert isinstance(pgm.component_update, IteratedUpdate)
    assert isinstance(pgm.posterior_draw, TransformDraw)
    assert type(pgm.reanchor).registry_name == "arcs"
    assert isinstance(pgm.prediction, PropagateParticles) and isinstance(pgm.kernel_update, AfterGapKernels)


def test_a_scenario_swaps_in_a_third_partys_step_by_name(reg):
    scen = load_scenario("quick", reg, overrides={"filter": {"component_update": "test-counting"}})
    pgm = scen.build("filter", reg)
    assert isinstance(pgm.component_update, CountingUpdate)
    before = CountingUpdate.calls
    _linear_run(pgm)
    assert CountingUpdate.calls == before + 3


def test_the_pgms_own_settings_reach_the_step_built_for_a_scenario(reg):
    scen = load_scenario("quick", reg, overrides={"filter": {"update_iterations": 3, "component_likelihood": "prior",
                                                             "reanchor": "across-gaps", "reanchor_starts": 2,
                                                             "kernel_ess": 0.5, "velocity_noise_kms_per_sqrt_day": 1e-6}})
    pgm = scen.build("filter", reg)
    assert (pgm.component_update.update_iterations, pgm.component_update.component_likelihood) == (3, "prior")
    assert isinstance(pgm.reanchor, AcrossGapsReanchor) and pgm.reanchor.reanchor_starts == 2
    assert isinstance(pgm.kernel_update, AfterGapKernels) and pgm.kernel_update.kernel_ess == 0.5
    assert isinstance(pgm.prediction, PropagateParticles) and pgm.prediction.velocity_noise_kms_per_sqrt_day == 1e-6


def test_a_steps_own_table_in_a_scenario_keeps_its_values(reg):
    scen = load_scenario("quick", reg, overrides={"filter": {"component_update": {"name": "iterated",
                                                                                  "update_iterations": 4}}})
    pgm = scen.build("filter", reg)
    _linear_run(pgm)
    assert pgm._update.update_iterations == 4


def test_a_setting_made_differently_in_the_pgm_and_in_its_steps_table_is_refused(reg):
    scen = load_scenario("quick", reg, overrides={"filter": {"update_iterations": 3, "component_update": {
        "name": "iterated", "update_iterations": 4}}})
    with pytest.raises(ParameterError, match="update_iterations = 3 conflicts"):
        _linear_run(scen.build("filter", reg))


def test_an_unknown_step_name_is_refused_naming_the_parameter_and_the_choices():
    with pytest.raises(ParameterError, match="posterior_draw.*gaussian, transform"):
        PGMFilter(posterior_draw="kde")
    with pytest.raises(ParameterError, match="reanchor"):
        PGMFilter(reanchor=TransformDraw())


def test_a_step_given_as_a_component_is_used_as_given():
    filt = PGMFilter(n_particles=3000, n_components=2, component_update=EnsembleUpdate(), posterior_draw=GaussianDraw())
    by_name = PGMFilter(n_particles=3000, n_components=2, component_update="ensemble", posterior_draw="gaussian")
    a, b = _linear_run(filt), _linear_run(by_name)
    np.testing.assert_array_equal(a.samples.states, b.samples.states)


def test_a_step_left_at_its_defaults_takes_the_pgms_settings():
    filt = PGMFilter(n_particles=3000, n_components=2, update_iterations=3, component_update=IteratedUpdate())
    _linear_run(filt)
    assert filt._update.update_iterations == 3
    assert filt.component_update.update_iterations == 10, "the caller's step is not modified"


def test_pgm_paper_is_the_pgm_with_the_papers_settings():
    settings = preset_defaults(PaperPGMFilter)
    assert settings == {"component_update": "ensemble", "posterior_draw": "gaussian", "reanchor": "off",
                        "kept_spread": 1.0, "reacquire_factor": 1.0, "min_cluster_size": 12}
    assert PaperPGMFilter().get_params() == PGMFilter(**settings).get_params()
    a = _linear_run(PaperPGMFilter(n_particles=3000, n_components=3))
    b = _linear_run(PGMFilter(n_particles=3000, n_components=3, **settings))
    np.testing.assert_array_equal(a.samples.states, b.samples.states)
    np.testing.assert_array_equal(a.mixture.covariances, b.mixture.covariances)


def test_a_presets_parameters_are_listed_with_its_own_defaults(reg):
    docs = {p.name: p for p in param_docs(reg.get("filter", "pgm-paper").factory)}
    assert [p.name for p in param_docs(PGMFilter)] == list(docs)
    assert (docs["component_update"].default, docs["reanchor"].default, docs["n_particles"].default) == \
        ("ensemble", "off", 10000)
    assert docs["kept_spread"].meaning == {p.name: p for p in param_docs(PGMFilter)}["kept_spread"].meaning


def test_a_preset_instance_pickles_and_rebuilds_from_its_params():
    f = PaperPGMFilter(n_particles=500)
    g = pickle.loads(pickle.dumps(f))
    assert type(g) is PaperPGMFilter and g.get_params() == f.get_params()
    assert type(f)(**f.get_params()).get_params() == f.get_params()


def test_a_preset_of_an_unknown_parameter_is_refused():
    with pytest.raises(TypeError, match="no parameters.*n_particle"):
        preset(PGMFilter, "Bad", "A bad preset.", n_particle=10)


def test_kernels_off_leave_the_clusters_gaussians_at_every_update():
    assert AfterGapKernels(kernel_ess=0.0).start() is None and NoKernels().start() is None
    assert AfterGapKernels(kernel_ess=1.0).start() is not None


@pytest.mark.parametrize("cls, interface", [(IteratedUpdate, ComponentUpdate), (EnsembleUpdate, ComponentUpdate),
                                            (PropagateParticles, ParticlePrediction), (AfterGapKernels, KernelUpdate),
                                            (NoKernels, KernelUpdate),
                                            (TransformDraw, PosteriorDraw), (GaussianDraw, PosteriorDraw),
                                            (AcrossGapsReanchor, Reanchor), (NoReanchor, Reanchor)])
def test_each_builtin_step_implements_its_interface_and_rebuilds_from_its_params(cls, interface):
    step = cls()
    assert isinstance(step, interface)
    assert type(step)(**step.get_params()).get_params() == step.get_params()


def test_more_components_than_the_particles_hold_clusters_of_the_kept_size_are_refused():
    from cistrack.plugins.filters.pgm.filter import PGMFilter

    with pytest.raises(ParameterError, match=r"n_components' = 5000 .*must be <= 33: 10000 particles"):
        PGMFilter(n_particles=10000, n_components=5000)
    assert PGMFilter(n_particles=10000, n_components=33).n_components == 33
    assert PGMFilter(n_particles=10000, n_components=100, min_cluster_size=50).n_components == 100


def test_fewer_particles_than_a_six_dimensional_mixture_needs_are_refused():
    from cistrack.plugins.filters.pgm.filter import PGMFilter

    with pytest.raises(ParameterError, match=r"n_particles' = 5 .*must be >= 100: .*6-D state"):
        PGMFilter(n_particles=5, n_components=1)
    assert PGMFilter(n_particles=100, n_components=1).n_particles == 100
