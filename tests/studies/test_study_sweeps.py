"""Sweeps in study files: every scenario entry crossed with every combination of the swept
settings, applied like ``--set`` items after the study's overrides, validated before any run, and
named in the run ids and report groups; a study without a sweep names its runs as before."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from cistrack.errors import ConfigError
from cistrack.studies.study import base_scenario_name, plan_runs, sweep_label
from cistrack.studies.study_file import load_study

_SWEEP = '{"truth.maneuvers.delta_v_ms" = [0.01, 0.3, 1.0], "maneuvers.response" = ["none", "inflate"]}'


def _study(tmp_path: Path, scenarios: str, sweep: str | None = _SWEEP, extra: str = "") -> Path:
    p = tmp_path / "sweep.toml"
    p.write_text(f'name = "sweep"\nscenarios = {scenarios}\nfilters = ["pgm", "ukf"]\nseeds = [7001, 7002]\n'
                 + (f"sweep = {sweep}\n" if sweep else "") + extra)
    return p


def test_a_sweep_crosses_each_scenario_with_every_combination_and_names_it(tmp_path):
    _, specs, out = plan_runs(_study(tmp_path, '["example-1-burn"]'), tmp_path / "out")
    assert len(specs) == 3 * 2 * 2 * 2  # dv x response x filters x seeds
    ids = [s.run_id for s in specs]
    assert len(set(ids)) == len(ids)
    assert "example-1-burn[dv=0.3,resp=inflate]__pgm__uniform-range__seed7001" in ids
    assert "example-1-burn[dv=1,resp=none]__ukf__uniform-range__seed7002" in ids
    s = next(s for s in specs if s.run_id.startswith("example-1-burn[dv=0.3,resp=inflate]__ukf"))
    assert s.scenario_name == "example-1-burn[dv=0.3,resp=inflate]" and s.out_dir == str(out / "runs" / s.run_id)
    assert s.sweep == (("truth.maneuvers.delta_v_ms", 0.3), ("maneuvers.response", "inflate"))
    assert base_scenario_name(s.scenario_name, s.sweep) == "example-1-burn"
    # applied like --set: into the scenario's own tables, the rest of them kept
    assert s.overrides["truth"]["maneuvers"] == {"name": "impulse", "t_days": 3.62, "delta_v_ms": 0.3,
                                                 "direction": "in-track", "frame": "rtn-moon"}
    assert s.overrides["maneuvers"]["response"] == "inflate" and s.overrides["filter"] == {"name": "ukf"}
    # each combination is its own scenario: distinct fingerprints per seed
    assert len({sp.fingerprint for sp in specs}) == len(specs)


def test_a_study_without_a_sweep_names_its_runs_as_before(tmp_path):
    _, specs, _ = plan_runs(_study(tmp_path, '["example-1-burn"]', sweep=None), tmp_path / "out")
    assert [s.run_id for s in specs] == [f"example-1-burn__{f}__uniform-range__seed{n}"
                                         for f in ("pgm", "ukf") for n in (7001, 7002)]
    assert all(s.sweep == () and s.scenario_name == "example-1-burn" for s in specs)


def test_the_sweep_comes_after_the_overrides_and_before_the_command_lines_set(tmp_path):
    p = _study(tmp_path, '["example-1-burn"]', sweep='{"truth.maneuvers.delta_v_ms" = [0.1, 0.2]}',
               extra='[overrides]\ntruth = {orbit = "nrho-9-2", maneuvers = {name = "impulse", t_days = 2.0, '
                     'delta_v_ms = 5.0}}\n')
    _, specs, _ = plan_runs(p, tmp_path / "a")
    assert {(s.overrides["truth"]["maneuvers"]["t_days"], s.overrides["truth"]["maneuvers"]["delta_v_ms"])
            for s in specs} == {(2.0, 0.1), (2.0, 0.2)}
    _, specs, _ = plan_runs(p, tmp_path / "b", settings=["truth.maneuvers.t_days=3.0"])
    assert {(s.overrides["truth"]["maneuvers"]["t_days"], s.overrides["truth"]["maneuvers"]["delta_v_ms"])
            for s in specs} == {(3.0, 0.1), (3.0, 0.2)}


def test_a_scenario_entry_table_chooses_which_settings_sweep_it(tmp_path):
    entries = ('[{name = "example-1", sweep = false}, {name = "example-1", sweep = ["maneuvers.response"]}, '
               '"example-1-burn"]')
    p = _study(tmp_path, entries)
    _, specs, _ = plan_runs(p, tmp_path / "out")
    labels = sorted({s.scenario_name for s in specs})
    assert labels == sorted(["example-1", "example-1[resp=none]", "example-1[resp=inflate]",
                             *[f"example-1-burn[dv={dv},resp={r}]" for dv in ("0.01", "0.3", "1")
                               for r in ("none", "inflate")]])


def test_a_setting_that_does_not_apply_to_a_scenario_is_refused_naming_the_file_key_and_scenario(tmp_path):
    p = _study(tmp_path, '["example-1", "example-1-burn"]')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    text = str(exc.value)
    assert text.startswith(f"{p}: key 'sweep', setting 'truth.maneuvers.delta_v_ms' does not apply to scenario "
                           "'example-1' (")
    assert 'sweep = false' in text
    assert not (tmp_path / "out").exists()


def test_every_combination_is_validated_before_any_run(tmp_path):
    p = _study(tmp_path, '["example-1-burn"]', sweep='{"maneuvers.response" = ["inflate", "no-such-response"]}')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    assert "no-such-response" in str(exc.value) and str(p) in str(exc.value) and "key 'sweep'" in str(exc.value)


@pytest.mark.parametrize("sweep, match", [
    ("[1, 2]", "key 'sweep' must be a table"),
    ("{}", "key 'sweep' must be a table"),
    ('{"maneuvers.response" = []}', "setting 'maneuvers.response': must be a non-empty list"),
    ('{"maneuvers.response" = "none"}', "setting 'maneuvers.response': must be a non-empty list"),
    ('{"truth.maneuvers.delta_v_ms" = [0.1, 0.1]}', "repeats a value"),
    ('{"truth.maneuvers" = [{name = "impulse"}]}', "values must be numbers, strings or booleans"),
    ('{"truth..delta_v_ms" = [0.1]}', "not a dotted setting"),
    ('{"filter.n_particles " = [700]}', "not a dotted setting"),
    ('{"filter.n_particles" = [500], filter = {n_particles = [700]}}', "the same setting as 'filter.n_particles'"),
    ('{"seed" = [1, 2]}', "cannot be swept: the study's seeds"),
    ('{"filter.name" = ["pgm", "enkf"]}', "cannot be swept: filters are the study's key 'filters'"),
    ('{"iod.name" = ["noisy-range"]}', "cannot be swept: IOD methods"),
])
def test_a_malformed_sweep_is_refused_naming_the_file_and_key(tmp_path, sweep, match):
    p = _study(tmp_path, '["example-1-burn"]', sweep=sweep)
    with pytest.raises(ConfigError, match=match) as exc:
        load_study(p)
    assert str(p) in str(exc.value)


@pytest.mark.parametrize("entry, match", [
    ('{name = "example-1-burn", sweep = ["filter.n_particles"]}', "not a setting of the study's 'sweep'"),
    ('{name = "example-1-burn", sweep = "yes"}', "must be true, false or a list"),
    ('{name = "example-1-burn", seeds = [1]}', "unknown key 'seeds'"),
    ('{sweep = false}', "entries of 'scenarios' must be names"),
])
def test_a_malformed_scenario_entry_is_refused(tmp_path, entry, match):
    p = _study(tmp_path, f"[{entry}]")
    with pytest.raises(ConfigError, match=match):
        load_study(p)


def test_a_sweep_written_as_nested_tables_is_the_same_sweep(tmp_path):
    a = plan_runs(_study(tmp_path, '["example-1-burn"]'), tmp_path / "a")[1]
    p = tmp_path / "nested.toml"
    p.write_text('name = "sweep"\nscenarios = ["example-1-burn"]\nfilters = ["pgm", "ukf"]\nseeds = [7001, 7002]\n'
                 '[sweep.truth.maneuvers]\ndelta_v_ms = [0.01, 0.3, 1.0]\n[sweep.maneuvers]\nresponse = ["none", "inflate"]\n')
    b = plan_runs(p, tmp_path / "b")[1]
    assert [s.run_id for s in a] == [s.run_id for s in b]


def test_labels_are_compact_stable_and_one_path_component():
    combo = (("truth.maneuvers.delta_v_ms", 1.0), ("maneuvers.response", "inflate"), ("truth.maneuvers.t_days", 5.6))
    assert sweep_label("example-1-burn", combo) == "example-1-burn[dv=1,resp=inflate,t=5.6]"
    assert sweep_label("x", (("filter.n_particles", 500), ("iod.n_particles", 300))) == \
        "x[filter.n_particles=500,iod.n_particles=300]"  # two settings would share a name: the whole settings
    assert sweep_label("x", (("maneuvers.estimate", False),)) == "x[estimate=false]"
    assert sweep_label("x", ()) == "x"


def test_a_study_directory_plans_the_same_swept_runs_it_recorded(tmp_path):
    p = _study(tmp_path, '[{name = "example-1", sweep = ["maneuvers.response"]}, "example-1-burn"]')
    data, specs, out = plan_runs(p, tmp_path / "out")
    out.mkdir(parents=True)
    (out / "study.json").write_text(json.dumps({"source": str(p), **data, "settings": [],
                                                "run_seeds": sorted({s.seed for s in specs})}))
    _, again, _ = plan_runs(out)
    assert [(s.run_id, s.sweep, s.fingerprint) for s in again] == [(s.run_id, s.sweep, s.fingerprint) for s in specs]


def test_a_set_item_on_a_swept_setting_is_refused(tmp_path):
    p = _study(tmp_path, '["example-1-burn"]')
    for item in ("truth.maneuvers.delta_v_ms=0.5", 'truth.maneuvers={name="impulse", t_days=2.0}'):
        with pytest.raises(ConfigError, match="key 'sweep' already varies 'truth.maneuvers.delta_v_ms'"):
            plan_runs(p, tmp_path / "out", settings=[item])


@pytest.mark.parametrize("item", ["filter.name=ukf", 'filter={name="ukf"}'])
def test_a_set_item_naming_the_filter_of_a_study_that_lists_its_filters_is_refused(tmp_path, item):
    """--set filter.name=ukf had run the UKF in every entry, filed under the entries' names (probe M6)."""
    p = tmp_path / "m6.toml"
    p.write_text('name = "m6"\nscenarios = ["quick"]\nfilters = ["pgm", "enkf"]\nseeds = [1]\n')
    with pytest.raises(ConfigError, match="key 'filters' chooses the filter of each run"):
        plan_runs(p, tmp_path / "out", settings=[item])


def test_a_set_seed_is_refused_naming_the_studys_seeds(tmp_path):
    """--set seed=5 had been accepted and ignored (probe M6)."""
    p = _study(tmp_path, '["example-1-burn"]')
    with pytest.raises(ConfigError, match="--first-seed and --n-seeds"):
        plan_runs(p, tmp_path / "out", settings=["seed=5"])


def test_a_set_item_on_a_filter_parameter_is_still_taken(tmp_path):
    p = tmp_path / "m6.toml"
    p.write_text('name = "m6"\nscenarios = ["quick"]\nfilters = ["pgm", "enkf"]\nseeds = [1]\n')
    plan_runs(p, tmp_path / "out", settings=["filter.n_particles=300"])


def _quick_study(tmp_path: Path, sweep: str, filters: str = "") -> Path:
    p = tmp_path / "t13.toml"
    p.write_text(f'name = "t13"\nscenarios = ["quick"]\n{filters}seeds = [1]\nsweep = {sweep}\n')
    return p


def test_an_invalid_swept_value_is_blamed_on_the_sweep_not_on_the_filter_entry_it_replaces(tmp_path):
    p = _quick_study(tmp_path, '{ "filter.n_particles" = [50, 300] }',
                     filters='filters = [{ name = "pgm", n_particles = 300, n_components = 3 }]\n')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    text = str(exc.value)
    assert text.startswith(f"{p}: key 'sweep', setting 'filter.n_particles': value 50 is invalid: must be >= 100")
    assert "key 'filters'" not in text and "does not apply" not in text and "sweep = false" not in text


def test_an_invalid_swept_top_level_value_is_named_without_the_advice_for_settings_that_do_not_apply(tmp_path):
    p = _quick_study(tmp_path, '{ duration_days = [nan] }')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    text = str(exc.value)
    assert text.startswith(f"{p}: key 'sweep', setting 'duration_days': value nan is invalid: must be a finite "
                           "number > 0") and "sweep = false" not in text


def test_a_swept_parameter_the_scenarios_component_does_not_take_does_not_apply_to_it(tmp_path):
    p = _quick_study(tmp_path, '{ "filter.no_such_parameter" = [1, 2] }')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    text = str(exc.value)
    assert text.startswith(f"{p}: key 'sweep', setting 'filter.no_such_parameter' does not apply to scenario 'quick'")
    assert "unknown parameter 'no_such_parameter'" in text and '{name = "quick", sweep = false}' in text


def test_a_whole_number_swept_into_a_float_setting_is_refused_in_plain_words(tmp_path):
    """The scenario writes -1 as -1.0: the refusal had read "value -1 is invalid: .0 must be ..."."""
    p = _quick_study(tmp_path, '{ duration_days = [-1, 2] }')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    assert f"{p}: key 'sweep', setting 'duration_days': value -1 is invalid: must be a finite number > 0" in str(exc.value)


def test_the_advice_for_a_scenario_file_the_sweep_does_not_apply_to_quotes_its_entry_and_works(tmp_path):
    from importlib import resources

    text = resources.files("cistrack.scenarios").joinpath("example-1.toml").read_text()
    scenario = tmp_path / "mine.toml"
    scenario.write_text(text.replace('name = "example-1"', 'name = "inner-name"', 1))
    p = _study(tmp_path, f'["example-1-burn", "{scenario}"]')
    with pytest.raises(ConfigError) as exc:
        plan_runs(p, tmp_path / "out")
    advice = f'{{name = "{scenario}", sweep = false}}'
    assert "does not apply to scenario 'inner-name'" in str(exc.value) and advice in str(exc.value)
    p.write_text(p.read_text().replace(f'"{scenario}"]', f"{advice}]"))  # the advice, followed literally
    _, specs, _ = plan_runs(p, tmp_path / "out")
    assert {s.scenario_name.split("[")[0] for s in specs} == {"example-1-burn", "inner-name"}
