"""``ct.run(observers=...)`` takes objects that implement cistrack hooks and refuses anything else
before the run starts, naming the argument and the index."""
from __future__ import annotations

import pytest

import cistrack as ct
from cistrack.errors import ConfigError
from cistrack.runs.observers import checked_observers


class _Watcher:
    @ct.hookimpl
    def cistrack_run_started(self, run):
        pass


def test_an_object_implementing_no_hook_is_refused_naming_the_argument_and_its_index():
    with pytest.raises(ConfigError, match=r"^observers\[1\]: object object implements no cistrack hook.*"
                                          r"@cistrack\.hookimpl.*cistrack_run_started"):
        ct.run("quick", observers=[_Watcher(), object()])


def test_observers_that_are_not_a_list_are_refused():
    with pytest.raises(ConfigError, match=r"^observers: must be a list of observers.*got int"):
        ct.run("quick", observers=3)


def test_an_object_with_a_hook_implementation_is_an_observer():
    watcher = _Watcher()
    assert checked_observers((watcher,)) == [watcher]
