"""The registry finds components through entry points, reports broken plugins by name, rejects
duplicates naming both sources, and helps with unknown names."""
from __future__ import annotations

import subprocess
import sys
from importlib import metadata
from pathlib import Path

import pytest

from cistrack.errors import DuplicateComponentError, UnknownComponentError
from cistrack.plugin.registry import AUTOLOAD_ENV, Registry, load_registry

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ROOT / "tests" / "plugin_packages"


def _pip(*args: str) -> None:
    subprocess.run([sys.executable, "-m", "pip", "--disable-pip-version-check", "-q", *args],
                   check=True, capture_output=True, text=True)


@pytest.fixture(scope="module")
def third_party_plugins():
    """Install a real third-party plugin and a broken one into this environment, then remove them."""
    _pip("install", "--no-deps", "--no-build-isolation", str(PACKAGES / "example"), str(PACKAGES / "broken"),
         str(PACKAGES / "duplicate"))
    import importlib
    importlib.invalidate_caches()
    yield
    _pip("uninstall", "-y", "cistrack-example-plugin", "cistrack-broken-plugin", "cistrack-duplicate-plugin")
    importlib.invalidate_caches()


def test_every_builtin_entry_point_loads_without_failure():
    reg = load_registry(autoload_third_party=False)
    assert [f for f in reg.failures if f.distribution == "cistrack"] == []
    declared = {ep.name for ep in metadata.entry_points(group="cistrack") if ep.dist.metadata["Name"] == "cistrack"}
    loaded = {ep for dist, ep, _ in reg.plugins if dist == "cistrack"}
    assert loaded == declared


@pytest.mark.parametrize("kind,name", [
    ("dynamics", "cr3bp"), ("dynamics", "twobody"), ("sensor", "ground-telescope"),
    ("iod", "noisy-range"), ("iod", "uniform-range"), ("iod", "uniform-range-velocity-bound"), ("iod", "gauss"),
    ("clustering", "kmeans"), ("clustering", "gmm"), ("clustering", "bic"),
    ("filter", "pgm"), ("filter", "ukf"), ("filter", "enkf"), ("filter", "sir"),
    ("orbit", "nrho-9-2"), ("recorder", "rerun"),
])
def test_builtin_component_is_registered_by_the_cistrack_distribution(kind, name):
    reg = load_registry(autoload_third_party=False)
    entry = reg.get(kind, name)
    assert entry.distribution == "cistrack"
    assert entry.version == metadata.version("cistrack")


def test_third_party_plugin_is_discovered_with_its_distribution(third_party_plugins):
    reg = load_registry(autoload_third_party=True)
    entry = reg.get("clustering", "one-cluster")
    assert (entry.distribution, entry.version, entry.entry_point) == ("cistrack-example-plugin", "0.3.1", "one-cluster")


def test_broken_plugin_is_reported_and_the_others_still_load(third_party_plugins):
    reg = load_registry(autoload_third_party=True)
    broken = [f for f in reg.failures if f.distribution == "cistrack-broken-plugin"]
    assert len(broken) == 1
    assert broken[0].entry_point == "broken"
    assert "cistrack_dependency_that_is_not_installed" in broken[0].error
    assert "one-cluster" in reg.names("clustering")
    assert "pgm" in reg.names("filter")


def test_environment_variable_disables_third_party_autoloading(third_party_plugins, monkeypatch):
    monkeypatch.setenv(AUTOLOAD_ENV, "1")
    reg = load_registry()
    assert "one-cluster" not in reg.names("clustering")
    assert reg.failures == []
    assert "pgm" in reg.names("filter")


@pytest.mark.parametrize("value, loaded", [("on", False), ("YES", False), ("true", False), ("0", True),
                                           ("off", True), ("", True)])
def test_the_autoload_switch_takes_every_yes_no_spelling(third_party_plugins, monkeypatch, value, loaded):
    monkeypatch.setenv(AUTOLOAD_ENV, value)
    assert ("one-cluster" in load_registry().names("clustering")) is loaded


def test_an_autoload_switch_that_is_neither_yes_nor_no_is_refused_by_name(monkeypatch):
    from cistrack.errors import ConfigError

    monkeypatch.setenv(AUTOLOAD_ENV, "bogus")
    with pytest.raises(ConfigError, match=f"{AUTOLOAD_ENV}='bogus'"):
        load_registry()


def test_cli_plugins_lists_builtins_and_third_party_with_distributions(third_party_plugins):
    out = subprocess.run([sys.executable, "-m", "cistrack.cli", "plugins"], capture_output=True, text=True,
                         check=True).stdout
    assert "one-cluster" in out and "cistrack-example-plugin 0.3.1" in out
    assert "pgm" in out and "cistrack " + metadata.version("cistrack") in out
    assert "plugins that failed to load" in out and "cistrack-broken-plugin" in out


def test_duplicate_name_is_rejected_naming_both_sources():
    reg = Registry()
    reg.add("clustering", "kmeans", object, "pkg-a", "1.0", "ep-a")
    with pytest.raises(DuplicateComponentError, match=r"pkg-a 1\.0.*ep-a.*pkg-b 2\.0.*ep-b"):
        reg.add("clustering", "kmeans", object, "pkg-b", "2.0", "ep-b")


def test_unknown_name_lists_available_and_suggests_the_closest():
    reg = load_registry(autoload_third_party=False)
    with pytest.raises(UnknownComponentError) as info:
        reg.get("filter", "pgn")
    msg = str(info.value)
    assert "available: enkf, pgm, pgm-paper, rpf, sir, ukf" in msg
    assert "Did you mean 'pgm'?" in msg


def test_unknown_kind_lists_the_kinds():
    reg = Registry()
    with pytest.raises(UnknownComponentError, match="kinds are: dynamics, sensor"):
        reg.names("estimator")


def test_import_core_fails_and_import_cistrack_works_outside_the_source_tree(tmp_path):
    bad = subprocess.run([sys.executable, "-c", "import core"], cwd=tmp_path, capture_output=True, text=True)
    assert bad.returncode != 0 and "No module named 'core'" in bad.stderr
    bad = subprocess.run([sys.executable, "-c", "import plugins"], cwd=tmp_path, capture_output=True, text=True)
    assert bad.returncode != 0
    ok = subprocess.run([sys.executable, "-c", "import cistrack, cistrack.plugins.filters; print('ok')"],
                        cwd=tmp_path, capture_output=True, text=True)
    assert ok.stdout.strip() == "ok", ok.stderr



def test_a_plugin_reusing_a_taken_name_is_reported_naming_both_and_the_builtin_stays(third_party_plugins):
    reg = load_registry(autoload_third_party=True)
    dup = [f for f in reg.failures if f.distribution == "cistrack-duplicate-plugin"]
    assert len(dup) == 1
    assert "clustering 'kmeans' is registered twice" in dup[0].error
    assert "by cistrack " in dup[0].error and "cistrack-duplicate-plugin 1.2.0" in dup[0].error
    assert reg.get("clustering", "kmeans").distribution == "cistrack"
    assert "kmeans-again" not in reg.names("clustering")  # what it added before failing is taken back
