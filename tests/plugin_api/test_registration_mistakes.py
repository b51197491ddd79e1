"""What the registry refuses from a plugin, and how: each refusal names the plugin (distribution,
entry point), the kind and the name, so that a plugin author's slip never registers something
that fails later under another name, or registers nothing without a word."""
from __future__ import annotations

import itertools
from pathlib import Path

import pytest

from cistrack.errors import ParameterError
from cistrack.plugin.registry import Registry, load_registry
from cistrack.plugins.filters.ukf import UKFFilter
from plugin_site import plugin_site  # tests/ is on sys.path

_COUNT = itertools.count()

UNMARKED = '''
from cistrack.plugins.filters.ukf import UKFFilter


class Mine(UKFFilter):
    """A filter registered by a hook its author forgot to mark."""


def cistrack_register(registry):
    registry.add("filter", "unmarked-filter", Mine)
'''


def _plugin_on_path(tmp_path: Path, monkeypatch, body: str) -> str:
    """A distribution ``cistrack-slip`` whose one entry point is a module with ``body``, on sys.path;
    returns the entry point's (and module's) name, new for each test (modules are imported once)."""
    module = f"slip_plugin_{next(_COUNT)}"
    plugin_site(tmp_path, "cistrack-slip", "0.1", {module: body})
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delenv("CISTRACK_DISABLE_PLUGIN_AUTOLOAD", raising=False)
    return module


def test_a_cistrack_register_not_marked_as_a_hook_is_listed_as_a_plugin_that_failed_to_load(tmp_path, monkeypatch):
    module = _plugin_on_path(tmp_path, monkeypatch, UNMARKED)
    reg = load_registry()
    failed = [str(f) for f in reg.failures if f.entry_point == module]
    assert failed == [f"cistrack-slip: entry point '{module}' failed: its module {module} has cistrack_register but "
                      "it is not marked @cistrack.hookimpl (from cistrack.api import hookimpl), so cistrack never "
                      "calls it"]
    assert "unmarked-filter" not in reg.names("filter")


def _add(factory, name: str = "slip-filter", kind: str = "filter") -> None:
    Registry().add(kind, name, factory, "cistrack-slip", "0.1", "slip")


def test_a_factory_that_is_not_a_class_is_refused_naming_the_plugin_the_kind_and_the_name():
    with pytest.raises(ParameterError, match=r"^plugin cistrack-slip 0\.1 \(entry point 'slip'\): filter "
                                             r"'slip-filter' must be registered as a class .* got int 42$"):
        _add(42)


def test_an_instance_is_refused_as_a_factory_it_would_be_shared_by_every_run():
    with pytest.raises(ParameterError, match="filter 'slip-filter' must be registered as a class .* got UKFFilter"):
        _add(UKFFilter())


@pytest.mark.parametrize("name", ["has space", "tab\tname", "new\nline", "bell\x07", ""])
def test_a_name_with_whitespace_or_control_characters_is_refused(name):
    with pytest.raises(ParameterError, match=r"plugin cistrack-slip 0\.1 .*filter name .* is not allowed"):
        _add(UKFFilter, name)


HALF_MARKED = '''
from cistrack.api import hookimpl
from cistrack.plugins.filters.ukf import UKFFilter


class Mine(UKFFilter):
    """A filter registered by a marked hook beside an observer hook its author forgot to mark."""


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "half-marked-filter", Mine)


def cistrack_step_updated(run, step):
    pass
'''


def test_an_unmarked_hook_beside_a_marked_one_fails_the_plugin_naming_it(tmp_path, monkeypatch):
    module = _plugin_on_path(tmp_path, monkeypatch, HALF_MARKED)
    reg = load_registry()
    failed = [str(f) for f in reg.failures if f.entry_point == module]
    assert len(failed) == 1 and "has cistrack_step_updated but it is not marked @cistrack.hookimpl" in failed[0]
    assert "half-marked-filter" not in reg.names("filter")



MISSPELT = '''
from cistrack.api import hookimpl
from cistrack.plugins.filters.ukf import UKFFilter


class Mine(UKFFilter):
    """A filter registered beside an observer hook whose name its author misspelt."""


@hookimpl
def cistrack_register(registry):
    registry.add("filter", "misspelt-hook-filter", Mine)


@hookimpl
def cistrack_run_finish(run, summary):
    pass
'''


def test_a_marked_function_named_after_no_hook_fails_the_plugin_naming_it_and_the_hook_meant(tmp_path, monkeypatch):
    """Probe L9: ``cistrack_run_finish`` (for cistrack_run_finished) marked @hookimpl was never called,
    without a word; pluggy's check_pending refuses exactly this."""
    module = _plugin_on_path(tmp_path, monkeypatch, MISSPELT)
    reg = load_registry()
    failed = [str(f) for f in reg.failures if f.entry_point == module]
    assert len(failed) == 1
    assert (f"its module {module} marks @cistrack.hookimpl 'cistrack_run_finish' (did you mean "
            "'cistrack_run_finished'?), which is no cistrack hook, so cistrack never calls it") in failed[0]
    assert "the hooks are: cistrack_register, " in failed[0]
    assert "misspelt-hook-filter" not in reg.names("filter") and "ukf" in reg.names("filter")


@pytest.mark.parametrize("second, warned", [("otherplug", True), ("cistrack", False)])
def test_a_reader_claiming_a_suffix_another_distributions_reader_claims_is_warned_about(caplog, second, warned):
    """Files ending so can then be read only with the format named; one distribution's own two
    readings of a suffix are its own affair."""
    from cistrack.plugins.readers.ades_psv import AdesPsvReader

    class OtherPsv(AdesPsvReader):
        """Another format whose files end in .psv."""

    reg = Registry()
    reg.add("reader", "ades-psv", AdesPsvReader, distribution="cistrack")
    with caplog.at_level("WARNING", logger="cistrack"):
        reg.add("reader", "other-psv", OtherPsv, distribution=second)
    said = f"reader 'other-psv' ({second}" in caplog.text and "claims .psv, as reader 'ades-psv'" in caplog.text
    assert said == warned and ("measurements.reader.name" in caplog.text) == warned


SPECNAMED = '''
from cistrack.api import hookimpl


@hookimpl(specname="cistrack_run_finished")
def on_finish(run, summary):
    return None
'''


def test_a_lifecycle_hook_given_by_specname_under_another_name_is_registered(tmp_path, monkeypatch):
    """@hookimpl(specname="cistrack_run_finished") on a function named otherwise had left its plugin
    unregistered, its hook never called, without a word (probe M11)."""
    from cistrack.runs.observers import make_plugin_manager

    module = _plugin_on_path(tmp_path, monkeypatch, SPECNAMED)
    pm = make_plugin_manager([], load_registry())
    assert any(getattr(i.plugin, "__name__", "") == module for i in pm.hook.cistrack_run_finished.get_hookimpls())
