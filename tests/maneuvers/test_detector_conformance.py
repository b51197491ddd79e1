"""The maneuver-detector conformance checks: the built-ins pass them, a third-party detector written
from docs/plugins.md alone passes them (the documented example itself, run from the page), and
each check fails the detector that breaks its rule."""
from __future__ import annotations

import math
import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from cistrack.interfaces.component import check_range
from cistrack.interfaces.maneuvers import Detection, ManeuverDetector
from cistrack.model.innovation import innovation
from cistrack.plugin.registry import Registry
from cistrack.plugins.maneuvers.detectors import MixtureLikelihoodDetector, NisWindowDetector
from cistrack.testing import ConformanceError, check_plugin, check_registered, parametrize_with_checks

DOCS = Path(__file__).resolve().parents[2] / "docs" / "plugins.md"


def _documented_plugin(monkeypatch) -> types.ModuleType:
    """The maneuver-detector example of docs/plugins.md, as an importable module of a third-party
    package (the picklability check pickles the class by its module's name)."""
    blocks = re.findall(r"```python\n(.*?)```", DOCS.read_text(encoding="utf-8"), flags=re.S)
    code = next(b for b in blocks if "ManeuverDetector" in b and "cistrack_register" in b)
    module = types.ModuleType("third_party_detector")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    exec(compile(code, str(DOCS), "exec"), module.__dict__)
    return module


@parametrize_with_checks([NisWindowDetector, MixtureLikelihoodDetector])
def test_built_in_detectors_pass(component, check):
    check(component)


def test_a_third_party_detector_written_from_the_docs_passes_the_suite(monkeypatch):
    plugin = _documented_plugin(monkeypatch)
    reg = Registry()
    plugin.cistrack_register(reg)
    results = check_registered("nis-jump", "maneuver-detector", reg)
    assert [str(r) for r in results if not r.passed] == []
    assert {r.name for r in results} >= {"deterministic", "reset_forgets", "false_alarms_within_the_declared_level",
                                         "detects_a_step_within_five_updates"}


class _Base(ManeuverDetector):
    """A one-update NIS detector to break one rule at a time.

    Parameters
    ----------
    false_alarm : float
        Per-update false-alarm probability.
    """

    def __init__(self, false_alarm: float = 1e-4) -> None:
        self.false_alarm = check_range(self, "false_alarm", false_alarm, 0.0, 0.5, lo_open=True)
        self.reset()

    def reset(self) -> None:
        self._last = None

    def _surprise(self, t, prior, measurements, sensor) -> float:
        inn = innovation(prior, list(measurements), sensor)
        return float(inn.nis / len(inn.names))

    def observe(self, t, prior, measurements, sensor):
        stat = self._surprise(t, prior, measurements, sensor)
        before = t if self._last is None else self._last
        self._last = t
        fired = stat > 10.0
        return stat, (Detection(t, stat, 10.0, "test", t_burn_bounds=self._bounds(before, t)) if fired else None)

    def _bounds(self, before, t):
        return (before, t)


class _AlwaysFires(_Base):
    def _surprise(self, *args):
        return 11.0


class _NeverFires(_Base):
    def _surprise(self, *args):
        return 0.0


class _Unseeded(_Base):
    def _surprise(self, *args):
        return float(np.random.default_rng().random())


class _Remembers(_Base):
    """reset() forgets the last time but not a count of updates folded into the statistic."""

    _count = 0

    def _surprise(self, *args):
        self._count += 1
        return super()._surprise(*args) + 1e-3 * self._count


class _BoundsAfterT(_Base):
    def _bounds(self, before, t):
        return (t, t + 1.0)


class _BoundsAfterTheBurn(_Base):
    def _bounds(self, before, t):
        return (t, t)


@pytest.mark.parametrize(("cls", "failing"), [
    (_AlwaysFires, "false_alarms_within_the_declared_level"),
    (_NeverFires, "detects_a_step_within_five_updates"),
    (_Unseeded, "deterministic"),
    (_Remembers, "reset_forgets"),
    (_BoundsAfterT, "observe_returns_a_statistic_and_a_detection_or_none"),
    (_BoundsAfterTheBurn, "detects_a_step_within_five_updates"),
])
def test_each_check_fails_the_detector_that_breaks_its_rule(cls, failing):
    with pytest.raises(ConformanceError) as err:
        check_plugin(cls)
    failed = {r.name for r in err.value.results if not r.passed}
    assert failing in failed, str(err.value)


def test_the_rule_breakers_pass_everything_else_when_fixed():
    assert check_plugin(_Base).passed
    assert math.isclose(-math.log10(_Base().false_alarm), 4.0)


class _NanStatistic(_Base):
    def _surprise(self, *args):
        return float("nan")


def _failed(cls) -> dict[str, str]:
    with pytest.raises(ConformanceError) as err:
        check_plugin(cls)
    return {r.name: r.message for r in err.value.results if not r.passed}


def test_a_nan_statistic_is_reported_as_not_finite_and_not_as_randomness_or_memory():
    """NaN != NaN had made 'deterministic' and 'reset_forgets' fail with false advice."""
    failed = _failed(_NanStatistic)
    assert "the statistic nan is not a finite float" in failed["observe_returns_a_statistic_and_a_detection_or_none"]
    assert "deterministic" not in failed and "reset_forgets" not in failed


def test_a_burn_window_after_the_step_is_reported_in_plain_numbers():
    why = _failed(_BoundsAfterTheBurn)["detects_a_step_within_five_updates"]
    assert re.search(r"t_burn_bounds \(\d\.\d+, \d\.\d+\) starts after \d\.\d+, the last update", why), why
    assert "np.float64" not in why
