"""Hostile input, round 5: each case was a traceback, a silent acceptance, a NaN in a result file or a
wrong end state, and is now refused by name or handled. Third-party components are written here as
a plugin author would (subclasses of the interfaces, added to a registry), run through the real
pipeline."""
from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from cistrack.cli.main import main
from cistrack.errors import ConfigError, FilterError
from cistrack.interfaces.clustering import Clusterer
from cistrack.interfaces.schedule import Schedule
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

REAL_DATA = Path(__file__).resolve().parents[1] / "core" / "scenarios" / "real_data"


def _strict_json(path) -> dict:
    """The file's JSON, refusing NaN and infinities as strict JSON readers do."""
    def refuse(name):
        raise AssertionError(f"{path}: {name} is not JSON")
    return json.loads(path.read_text(), parse_constant=refuse)


# --- a collapsed particle filter: no NaN entropy, a strict manifest ----------------------------

def test_a_collapsed_particle_filter_writes_a_finite_entropy_and_a_strict_manifest(tmp_path, capsys):
    out = tmp_path / "sir"
    rc = main(["run", "quick", "--set", 'filter={name="sir", n_particles=100, resample_threshold=0}',
               "--out", str(out), "--quiet"])
    assert rc == 0
    final = _strict_json(out / "manifest.json")["summary"]["final"]
    assert np.isfinite(final["entropy"])
    assert "RuntimeWarning" not in capsys.readouterr().err


# --- a third-party schedule that breaks its contract -----------------------------------------

class _BadSchedule(Schedule):
    """Evenly spaced times inside each pass, then spoiled as ``how`` says."""

    def __init__(self, how: str = "none"):
        self.how = how

    def plan(self, passes, t_end, rng):
        t = np.concatenate([np.linspace(p.start, p.end, 12)[1:-1] for p in passes])
        if self.how == "after":
            return np.append(t, t_end + 5.0)
        if self.how == "between":
            return np.sort(np.append(t, 0.5 * (passes[0].end + passes[1].start)))
        if self.how == "nan":
            return np.append(t, np.nan)
        if self.how == "2d":
            return np.stack([t, t], axis=1)
        if self.how == "text":
            return ["soon"]
        if self.how == "unsorted":
            return t[::-1]
        return t


@pytest.mark.parametrize("how, said", [("after", "outside the run"), ("between", "outside every visibility pass"),
                                       ("nan", "NaN or infinite"), ("2d", "shape"), ("text", "not times"),
                                       ("unsorted", "do not increase strictly")])
def test_a_schedule_breaking_its_contract_is_refused_by_name(how, said):
    reg = load_registry()
    reg.add("schedule", "bad-schedule", _BadSchedule)
    scen = load_scenario("quick", reg, overrides={"schedule": {"name": "bad-schedule", "how": how}})
    with pytest.raises(ConfigError, match=said) as info:
        run_scenario(scen, seed=1, registry=reg)
    assert "[schedule] 'bad-schedule': plan()" in str(info.value)


def test_a_schedule_keeping_its_contract_runs():
    reg = load_registry()
    reg.add("schedule", "bad-schedule", _BadSchedule)
    scen = load_scenario("quick", reg, overrides={"schedule": {"name": "bad-schedule"}, "duration_days": 2.0})
    assert run_scenario(scen, seed=1, registry=reg).summary.status == "finished"


# --- a third-party clusterer that breaks its contract ----------------------------------------

class _BadClusterer(Clusterer):
    """Two halves labelled 0 and 1, then spoiled as ``how`` says."""

    def __init__(self, how: str = "none"):
        self.how = how

    def cluster(self, x, rng):
        labels = (np.arange(x.shape[0]) >= x.shape[0] // 2).astype(int)
        if self.how == "huge":
            return labels * 10 ** 12
        if self.how == "half":
            return labels + 0.5
        if self.how == "text":
            return np.array(["a"] * x.shape[0])
        if self.how == "short":
            return labels[:-1]
        if self.how == "raise":
            raise ValueError("the plugin's own bug")
        if self.how == "nan":
            return np.full(x.shape[0], np.nan)
        if self.how == "nothing":
            return None
        if self.how == "gappy":  # {0, 2}: the value 1 unused (probe L10)
            return labels * 2
        return labels


@pytest.mark.parametrize("how, said", [("huge", "not whole numbers from 0 to"), ("half", "not whole numbers"),
                                       ("text", "not labels"), ("short", "shape"),
                                       ("gappy", r"leave 1 of the values from 0 to 2 unused \(e\.g\. 1\); labels must "
                                                 r"use every value in \[0, M\)"),
                                       ("raise", r"cluster\(\) raised ValueError: the plugin's own bug")])
def test_a_clusterer_breaking_its_contract_is_named_at_the_filters_start(how, said, tmp_path, capsys):
    """The PGM clusters the IOD's cloud as it starts: a clusterer's bad labels or its own exception
    end the command with the clusterer named (not only the filter), never a traceback."""
    reg = load_registry()
    reg.add("clustering", "bad-clusterer", _BadClusterer)
    scen = load_scenario("quick", reg, overrides={"filter": {"clusterer": {"name": "bad-clusterer", "how": how},
                                                             "n_components": 2}})
    with pytest.raises(FilterError, match=said) as info:
        run_scenario(scen, seed=1, registry=reg, output_dir=tmp_path / "out")
    assert str(info.value).startswith("filter 'pgm': clusterer 'bad-clusterer': cluster() ")


def _clustered_with(how: str) -> FilterError:
    reg = load_registry()
    reg.add("clustering", "bad-clusterer", _BadClusterer)
    scen = load_scenario("quick", reg, overrides={"filter": {"clusterer": {"name": "bad-clusterer", "how": how},
                                                             "n_components": 2}})
    with pytest.raises(FilterError) as info:
        run_scenario(scen, seed=1, registry=reg)
    return info.value


def test_a_clusterer_returning_none_is_said_to_have_returned_none():
    assert "cluster() returned None, not labels (a (N,) array of whole numbers)" in str(_clustered_with("nothing"))


def test_nan_labels_are_refused_without_numpys_all_nan_warning_before_the_error():
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        error = _clustered_with("nan")
    assert "not whole numbers from 0 to 999 (none of them finite)" in str(error)
    assert not [w for w in seen if "All-NaN" in str(w.message)]


def test_a_clusterer_keeping_its_contract_runs():
    reg = load_registry()
    reg.add("clustering", "bad-clusterer", _BadClusterer)
    scen = load_scenario("quick", reg, overrides={"filter": {"clusterer": "bad-clusterer", "n_components": 2}})
    assert run_scenario(scen, seed=1, registry=reg).summary.status == "finished"


# --- n_components set in two places: refused when the scenario or study is read ---------------

def test_a_pgm_and_clusterer_component_count_conflict_is_refused_when_the_scenario_is_read():
    with pytest.raises(ConfigError, match=r"\[filter\]: filter 'pgm': n_components = 6 conflicts with the clusterer"):
        load_scenario("quick", overrides={"filter": {"n_components": 6,
                                                     "clusterer": {"name": "kmeans", "n_components": 2}}})


def test_a_study_with_that_conflict_is_refused_before_any_run(tmp_path):
    from cistrack.studies.study import plan_runs

    study = tmp_path / "st.toml"
    study.write_text('name = "st"\nscenarios = ["quick"]\nseeds = [1]\n'
                     'filters = [{name = "pgm", n_particles = 500, n_components = 3, '
                     'clusterer = {name = "kmeans", n_components = 2}}]\n')
    with pytest.raises(ConfigError, match="conflicts with the clusterer"):
        plan_runs(study, tmp_path / "out")
    assert not (tmp_path / "out").exists()



# --- a bad environment is refused before the results directory is made --------------------------

@pytest.mark.parametrize("variable, value", [("CISTRACK_NUM_THREADS", "0"), ("CISTRACK_KERNEL_DIR", "{file}")])
def test_a_bad_thread_count_or_kernel_directory_is_refused_before_the_results_directory(
        variable, value, tmp_path, monkeypatch, capsys):
    afile = tmp_path / "afile"
    afile.write_text("")
    monkeypatch.setenv(variable, value.format(file=afile))
    out = tmp_path / "out"
    assert main(["run", "quick", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert ("CISTRACK_NUM_THREADS" in err or "kernel cache directory" in err) and "Traceback" not in err
    assert not out.exists()


# --- a study's run-id clash names what clashed ---------------------------------------------------

def _study_file(tmp_path, body: str):
    p = tmp_path / "st.toml"
    p.write_text('name = "st"\nseeds = [0]\nfilters = [{name = "enkf", n_particles = 100}]\n' + body)
    return p


def test_a_scenario_listed_twice_is_refused_naming_it_and_the_run_id(tmp_path):
    from cistrack.studies.study import plan_runs

    with pytest.raises(ConfigError, match=r"two runs share the id 'quick__enkf__noisy-range__seed0': scenario 'quick' "
                                          r"is listed twice"):
        plan_runs(_study_file(tmp_path, 'scenarios = ["quick", "quick"]\n'), tmp_path / "out")


@pytest.mark.parametrize("filters, label", [
    ('[{name = "enkf", n_particles = 100}, {name = "enkf", n_particles = 200}]', "enkf"),
    ('[{name = "enkf", label = "x"}, {name = "pgm", label = "x"}]', "x"),
])
def test_two_filters_entries_that_label_their_runs_alike_are_refused_saying_to_give_a_label(tmp_path, filters, label):
    """Two PGM sizes had been refused as "scenario 'quick' is listed twice", which it was not."""
    from cistrack.studies.study import plan_runs

    p = tmp_path / "st.toml"
    p.write_text(f'name = "st"\nseeds = [0]\nscenarios = ["quick"]\nfilters = {filters}\n')
    with pytest.raises(ConfigError, match=rf"st.toml: entries 1 and 2 of 'filters' both label their runs '{label}'.*"
                                          r"give each a distinct 'label'"):
        plan_runs(p, tmp_path / "out")


def test_sweep_values_that_are_the_same_number_are_a_repeat(tmp_path):
    from cistrack.studies.study_file import load_study

    with pytest.raises(ConfigError, match="repeats a value.*2 and 2.0 are the same number"):
        load_study(_study_file(tmp_path, 'scenarios = ["quick"]\nsweep = { "duration_days" = [2.0, 2] }\n'))


# --- a run that failed before its custody was judged does not print an empty time ----------------

def test_custody_of_a_run_that_failed_before_it_was_judged_says_so():
    from cistrack.evaluation.verdicts import Verdict, verdict_lines

    class Summary:
        has_truth, custody_kept, custody_lost_step, custody_lost_t_days = True, False, 3, None
        status, verdict = "filter-failed", Verdict()

    custody = verdict_lines(Summary())[1]
    assert custody == "  custody: LOST at step 3 (the run ended filter-failed, before it was judged)"
    assert "- d" not in custody


# --- results are never written inside another run's part folders --------------------------------

def test_out_inside_an_earlier_runs_part_folder_is_refused(tmp_path, capsys):
    base = tmp_path / "base"
    quick = ["run", "quick", "--set", "duration_days=1.5", "--set", "iod.n_particles=300",
             "--set", "filter.n_particles=300", "--quiet"]
    assert main(quick + ["--out", str(base)]) == 0
    assert main(quick + ["--out", str(base / "steps" / "inner")]) == 2
    assert "lies inside the part folders of the run in" in capsys.readouterr().err
    assert not (base / "steps" / "inner").exists()


# --- a fit stopped before its records can be run again into its directory -----------------------

def test_a_fit_directory_holding_only_what_a_stopped_fit_wrote_takes_the_retry(tmp_path):
    """Interrupted after it merged the observations (before its filter run's manifest): the
    directory holds the fit's marker and merged files; the retry the message asks for is allowed."""
    from cistrack.results.output_paths import FIT_STARTED, check_output_dir

    d = tmp_path / "fit"
    d.mkdir()
    (d / FIT_STARTED).write_text("cistrack fit of X\n")
    (d / "observations.psv").write_text("# version=2022\n")
    (d / "observations-early.psv").write_text("# version=2022\n")
    assert check_output_dir(d, "--out", records=("manifest.json", "fit.json")) == d


def test_a_users_folder_with_an_observation_file_is_still_refused(tmp_path):
    from cistrack.results.output_paths import check_output_dir

    d = tmp_path / "mine"
    d.mkdir()
    (d / "observations.psv").write_text("# version=2022\n")
    with pytest.raises(ConfigError, match="is not empty and holds no cistrack"):
        check_output_dir(d, "--out", records=("manifest.json", "fit.json"))


def test_every_fit_directory_starts_with_its_marker(tmp_path):
    from cistrack.results.output_paths import FIT_STARTED

    rows = ["# version=2022", "trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat"] + [
        f"fast|CCD|711|2026-08-08T10:10:{10 * j:02d}.000Z|{79.0 + 5 * j:.6f}|{28.0 + j:.6f}|0.648|0.648|Gaia3"
        for j in range(4)]
    f = tmp_path / "lone.psv"
    f.write_text("\n".join(rows) + "\n")
    assert main(["fit", str(f), "--out", str(tmp_path / "out"), "--quiet"]) == 3
    assert (tmp_path / "out" / FIT_STARTED).is_file()


# --- residual plots of sites whose file names coincide ------------------------------------------

def test_sites_whose_plot_names_coincide_each_get_their_own_files():
    from cistrack.fitting.residual_plots import site_file_stems

    stems = site_file_stems(["a/b", "a_b", "711", "A_B"])
    assert stems["711"] == "residuals-711"
    assert len({s.casefold() for s in stems.values()}) == 4
    assert all(stems[k].startswith("residuals-a_b-") or stems[k].startswith("residuals-A_B-")
               for k in ("a/b", "a_b", "A_B"))


# --- round 6: the Python API ---------------------------------------------------------------------

def test_a_run_stopped_by_an_observer_is_not_judged_kept():
    import cistrack as ct
    from cistrack.api import hookimpl

    class Boom:
        @hookimpl
        def cistrack_step_updated(self, run, step):
            raise RuntimeError("boom from observer")

    r = ct.run("quick", settings={"duration_days": 1.6}, observers=[Boom()])
    assert r.summary.status == "failed"
    assert r.verdict.kind == "none" and "did not finish (failed)" in r.verdict.reason


@pytest.mark.parametrize("kwargs, said", [({"weights": [2.0, -1.0, 0.0, 0.0]}, "weights must be finite, non-negative"),
                                          ({"weights": [np.nan] * 4}, "weights must be finite"),
                                          ({"weights": [0.0] * 4}, "not all zero"),
                                          ({"labels": [-3, 7, 1, 0]}, "labels must be 4 whole numbers >= 0"),
                                          ({"epoch": "x"}, "epoch must be a finite time"),
                                          ({"epoch": float("nan")}, "epoch must be a finite time")])
def test_a_particle_cloud_refuses_what_no_belief_can_be(kwargs, said):
    from cistrack.model.belief import ParticleCloud

    args = {"states": np.ones((4, 6)), "epoch": 0.0, **kwargs}
    with pytest.raises(ValueError, match=said):
        ParticleCloud(**args)


@pytest.fixture(scope="module")
def filter_parts():
    from cistrack.model.belief import ParticleCloud

    reg = load_registry()
    rng = np.random.default_rng(1)
    states = np.array([1.02, 0.0, -0.18, 0.0, -0.1, 0.0]) + 1e-4 * rng.standard_normal((200, 6))
    return reg, ParticleCloud(states, 0.0), reg.create("dynamics", "cr3bp"), reg.create("sensor", "ground-telescope")


@pytest.mark.parametrize("name", ["pgm", "ukf", "enkf", "sir", "rpf"])
def test_a_filter_used_out_of_order_or_with_wrong_types_says_so(name, filter_parts):
    from cistrack.errors import CistrackError
    from cistrack.model.belief import ParticleCloud

    reg, cloud, dyn, sensor = filter_parts
    f = reg.create("filter", name, **({"n_particles": 200} if name != "ukf" else {}))
    with pytest.raises(CistrackError, match="call initialize"):
        f.diagnostics
    for bad in [(cloud, "cr3bp", sensor, np.random.default_rng(1)), (cloud, dyn, sensor, 5),
                (ParticleCloud(cloud.states[:1], 0.0), dyn, sensor, np.random.default_rng(1)),
                (ParticleCloud(cloud.states[:, :4], 0.0), dyn, sensor, np.random.default_rng(1))]:
        with pytest.raises(CistrackError):
            f.initialize(*bad)
    f.initialize(cloud, dyn, sensor, np.random.default_rng(1))
    with pytest.raises(CistrackError, match="a time in TU"):
        f.predict("0.005")
    with pytest.raises(CistrackError, match="needs a cistrack Measurement"):
        f.update("hello")


# --- round 6: maneuvers -------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["inflate", "impulse-samples", "reanchor"])
def test_a_response_wider_than_a_kilometre_per_second_is_refused(name):
    from cistrack.errors import ParameterError

    with pytest.raises(ParameterError, match=r"delta_v_sigma_ms.*must lie in \(0.0, 1000.0\]"):
        load_registry().create("maneuver-response", name, delta_v_sigma_ms=1e6)


def test_a_parameter_of_a_component_chosen_by_name_in_the_file_can_be_set_alone():
    """example-1-burn's file says response = "inflate"; --set maneuvers.response.delta_v_sigma_ms
    sets that component's parameter (it said "missing key 'name'")."""
    from cistrack.scenario.settings import apply_settings

    scen = apply_settings(load_scenario("example-1-burn"), ["maneuvers.response.delta_v_sigma_ms=0.5"])
    assert scen.raw["maneuvers"]["response"] == {"name": "inflate", "delta_v_sigma_ms": 0.5}


@pytest.mark.parametrize("items", [["maneuvers.response=reanchor", "maneuvers.response.delta_v_sigma_ms=0.5"],
                                   ["maneuvers.response.delta_v_sigma_ms=0.5", "maneuvers.response=reanchor"]])
def test_a_component_name_and_its_parameter_set_in_either_order_go_together(items):
    from cistrack.scenario.settings import parse_settings

    assert parse_settings(items) == {"maneuvers": {"response": {"name": "reanchor", "delta_v_sigma_ms": 0.5}}}


def test_an_array_with_a_wrong_element_names_the_element():
    from cistrack.scenario.settings import apply_settings

    with pytest.raises(ConfigError, match=r"key 'vector_ms\[0\]' = 'a' has type str; expected a number"):
        apply_settings(load_scenario("example-1-burn"), ['truth.maneuvers.vector_ms=["a", 1, 1]'])


# --- round 6: signals, paths, concurrency -------------------------------------------------------

@pytest.mark.parametrize("delay_s", [0.3, 0.6])
def test_ctrl_c_while_plugins_load_ends_the_command(tmp_path, delay_s):
    """Ctrl-C early (the registry loading its plugins): it was taken for a broken plugin and the run
    went on to exit 0, or failed blaming the scenario; now the command ends, status 130."""
    import signal
    import subprocess
    import sys
    import time

    # SIGINT as a terminal leaves it (a shell's background job, such as a CI script started with '&',
    # inherits it ignored, and a program started so rightly keeps ignoring it)
    proc = subprocess.Popen([sys.executable, "-m", "cistrack.cli", "run", "example-1", "--out", str(tmp_path / "r")],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    time.sleep(delay_s)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "raised while loading" not in err and "Traceback" not in err


def test_a_fit_into_a_directory_another_fit_is_writing_is_refused_at_once(tmp_path, capsys):
    """Two fits into one --out both exited 0 and left one object's fit.json beside the other's files."""
    import threading

    from cistrack.results.dir_lock import fit_lock

    d = tmp_path / "fit"
    d.mkdir()
    held, release = threading.Event(), threading.Event()

    def hold():
        with fit_lock(d):
            held.set()
            release.wait(60)

    t = threading.Thread(target=hold)
    t.start()
    held.wait(10)
    try:
        obs = REAL_DATA / "observations.psv"
        assert main(["fit", str(obs), "--out", str(d), "--quiet"]) == 2
    finally:
        release.set()
        t.join()
    assert "another 'cistrack fit'" in capsys.readouterr().err
    assert not (d / "fit.json").exists()


@pytest.mark.parametrize("command", [["run", "quick"], ["fit", "OBS"], ["study", "run", "quick-comparison"]])
def test_an_out_path_that_is_not_utf8_is_refused_before_any_work(command, tmp_path, capsys):
    import os

    bad = os.fsdecode(os.fsencode(str(tmp_path)) + b"/bad\xff")
    argv = [str(REAL_DATA / "observations.psv") if c == "OBS" else c for c in command]
    assert main(argv + ["--out", bad, "--quiet"]) == 2
    assert "not valid UTF-8" in capsys.readouterr().err
    assert not os.path.lexists(bad)


def test_a_recording_onto_a_disk_short_of_room_is_refused_before_the_run(tmp_path, monkeypatch):
    """rerun's file writer waits for ever once the disk is full (no signal ends it): a disk with
    less free room than a recording needs is refused up front. (The file system's answer is
    replaced: a test cannot fill a disk.)"""
    import collections
    import shutil

    from cistrack.errors import ParameterError

    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(10**9, 10**9 - 2_000_000, 2_000_000))
    with pytest.raises(ParameterError, match="only 2 MB free on the disk"):
        load_registry().create("recorder", "rerun", path=str(tmp_path / "x.rrd"))


INTERRUPT_ON_IMPORT = """
import sys
class Interrupt:
    def find_spec(self, name, path=None, target=None):
        if name == "cistrack.cli.main":
            raise KeyboardInterrupt
sys.meta_path.insert(0, Interrupt())
sys.argv = {argv!r}
import cistrack.cli
"""


def test_ctrl_c_while_the_command_module_loads_ends_with_130_and_no_traceback():
    """A Ctrl-C that lands while cistrack.cli is still importing (before the command's handlers
    exist: a loaded machine stretches that window) had given Python's KeyboardInterrupt traceback."""
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", INTERRUPT_ON_IMPORT.format(argv=["-m"])],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 130 and "Traceback" not in proc.stderr
    assert "cistrack: interrupted (SIGINT) while starting; nothing was done" in proc.stderr


def test_ctrl_c_while_python_code_imports_the_cli_is_the_callers_keyboard_interrupt():
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", INTERRUPT_ON_IMPORT.format(argv=["my_script.py"])],
                          capture_output=True, text=True, timeout=120)
    assert "KeyboardInterrupt" in proc.stderr and proc.returncode != 130
