"""A third party's maneuver detector or response that raises, or answers what its interface does
not promise (a NaN statistic, a burn window outside the run, a detection dated elsewhere, a cloud
the filter cannot start from), ends the run "failed" naming the plugin, its distribution and the
step: not a traceback, not a failure of the filter, never NaN or an impossible window in the
results (docs/plugins.md, "Maneuver detectors")."""
from __future__ import annotations

import re

import numpy as np
import pytest

from cistrack.interfaces.maneuvers import Detection, ManeuverDetector, ManeuverResponse
from cistrack.model.belief import ParticleCloud
from cistrack.plugin.registry import load_registry
from cistrack.runs.pipeline import run_scenario
from cistrack.scenario.loading import load_scenario

FIRES_AT = 6
"""The update (counted from 1) at which the test detector fires."""


class HDetector(ManeuverDetector):
    """Statistic 1.0 at each update; fires at update :data:`FIRES_AT`. ``how`` breaks it: "raise",
    "genexit" (raises GeneratorExit), "memory" (raises MemoryError), "none" (returns None), "nan" (a NaN statistic), "text" (the statistic "high"), "future" (a
    burn window after the detection), "late" (a detection dated 3 TU after its update)."""

    def __init__(self, how: str = "ok") -> None:
        self.how = how
        self.reset()

    def reset(self) -> None:
        self._seen = 0

    def observe(self, t, prior, measurements, sensor):
        self._seen += 1
        if self.how == "raise" and self._seen == FIRES_AT:
            raise KeyError("lost its key")
        if self.how == "genexit" and self._seen == FIRES_AT:
            raise GeneratorExit()  # a BaseException, like SystemExit: a generator helper can leak one
        if self.how == "memory" and self._seen == FIRES_AT:
            raise MemoryError("pretends to be out of memory")
        stat = {"nan": float("nan"), "text": "high"}.get(self.how, 1.0)
        if self.how == "none":
            return None
        if self._seen != FIRES_AT:
            return stat, None
        window = (t + 5.0, t + 10.0) if self.how == "future" else (t, t)
        return stat, Detection(t=t + (3.0 if self.how == "late" else 0.0), statistic=2.0, threshold=1.0,
                               t_burn_bounds=window)


class HResponse(ManeuverResponse):
    """The prior's particles as the new cloud, broken by ``how``: "raise", "nan" (one NaN state),
    "width" (states of 3 components), "epoch" (dated 10 TU after the detection), "list"."""

    def __init__(self, how: str = "ok") -> None:
        self.how = how

    def respond(self, detection, prior, dynamics, rng):
        states = np.array(prior.samples.states, dtype=float)
        if self.how == "raise":
            raise ValueError("fell over")
        if self.how == "nan":
            states[0, 0] = np.nan
        if self.how == "list":
            return [states]
        epoch = detection.t + (10.0 if self.how == "epoch" else 0.0)
        return ParticleCloud(states[:, :3] if self.how == "width" else states, epoch)


def _run(detector: str = "ok", response: str | None = None):
    reg = load_registry(autoload_third_party=False)
    reg.add("maneuver-detector", "h-det", HDetector, "hplug", "0.1", "hplug")
    reg.add("maneuver-response", "h-resp", HResponse, "hplug", "0.1", "hplug")
    table = {"detector": {"name": "h-det", "how": detector}, "estimate": False}
    if response is not None:
        table["response"] = {"name": "h-resp", "how": response}
    scen = load_scenario("quick", reg, overrides={"duration_days": 2.0, "maneuvers": table})
    return run_scenario(scen, seed=1, registry=reg).summary


def test_a_detector_that_follows_its_contract_runs_to_the_end():
    summary = _run()
    assert summary.status == "finished" and len(summary.maneuvers) == 1


DETECTOR = "maneuver-detector 'h-det' (hplug 0.1): "
RESPONSE = "maneuver-response 'h-resp' (hplug 0.1): "


@pytest.mark.parametrize("plugin, how, what", [
    ("detector", "raise", r"observe\(\) raised KeyError: 'lost its key' at step \d+, t = \d\.\d{3} d$"),
    ("detector", "genexit", r"observe\(\) raised GeneratorExit at step \d+, t = \d\.\d{3} d$"),
    ("detector", "none", r"observe\(\) at step \d+, t = \d\.\d{3} d returned NoneType, not \(statistic, Detection or None\)$"),
    ("detector", "nan", r"observe\(\) at step \d+, t = \d\.\d{3} d returned the statistic nan: NaN or infinite, not a finite"),
    ("detector", "text", r"observe\(\) at step \d+, t = \d\.\d{3} d returned the statistic 'high': a str, not a finite"),
    ("detector", "future", r"returned a Detection whose t_burn_bounds \(\d+\.\d{3} d, \d+\.\d{3} d\) are not finite times "),
    ("detector", "late", r"returned a Detection whose t = \d+\.\d{3} d is not the update's time \d\.\d{3} d$"),
    ("response", "raise", r"respond\(\) raised ValueError: fell over at step \d+, t = \d\.\d{3} d$"),
    ("response", "nan", r"respond\(\) returned a cloud whose states are not all finite \(1 of \d+ hold NaN or inf\)"),
    ("response", "width", r"respond\(\) returned a cloud with states of shape \(\d+, 3\) for the detection at \d\.\d{3} d"),
    ("response", "epoch", r"respond\(\) returned a cloud at t = \d+\.\d{3} d, not at the detection's \d\.\d{3} d$"),
    ("response", "list", r"respond\(\) returned list for the detection at \d\.\d{3} d, not a ParticleCloud or None$"),
])
def test_a_detector_or_response_breaking_its_contract_fails_the_run_naming_it_and_the_step(plugin, how, what):
    summary = _run(**{plugin: how})
    assert summary.status == "failed"  # not "filter-failed": the filter is not at fault
    assert summary.failure.startswith(DETECTOR if plugin == "detector" else RESPONSE)
    assert re.search(what, summary.failure), summary.failure


def test_a_detector_running_out_of_memory_fails_the_run_with_a_memory_error_naming_it_and_the_step():
    summary = _run(detector="memory")
    assert summary.status == "failed"
    assert summary.failure.startswith(f"MemoryError: {DETECTOR}observe() ran out of memory at step "), summary.failure
    assert summary.failure.endswith("(MemoryError: pretends to be out of memory)")
