"""Custody: whether the filter still holds the target, judged in the run's metric stage.

:class:`CustodyMetric` is the metric stage ``custody`` (:mod:`cistrack.evaluation.metric_stage`;
it needs the ``belief`` stage's truth log-likelihood and HDR level). It judges each update step
against a :class:`CustodyRule`, adds the ``custody`` metric (1 kept, 0 lost) to every table step
of a run with a truth, and hands the run's :class:`Verdict` to the summary. It also observes
``cistrack_run_failed`` (the filter raised: "filter-failed").

Extending: a verdict has a ``kind`` and a ``reason``. Further judges (consistency without a
truth, divergence, ...) can subclass :class:`CustodyMetric` (override :meth:`judge`) or be
metric stages or observers of their own that produce a :class:`Verdict`.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from cistrack import units
from cistrack.astro.primaries import MU_EARTH_MOON
from cistrack.evaluation.metric_stage import StepMetric
from cistrack.plugin.hookspecs import hookimpl
from cistrack._moved import renamed_names

__all__ = ["CustodyRule", "Verdict", "CustodyMetric", "KEPT_KINDS", "VERDICT_KINDS"]

KEPT_KINDS: tuple[str, ...] = ("kept", "tracking", "not-converged")
"""Verdict kinds under which custody is kept (``custody_kept`` is True)."""
VERDICT_KINDS: tuple[str, ...] = ("tracking", "not-converged", "lost", "diverged", "filter-failed",
                                  "no-truth")
"""Final verdict kinds of a run."""


COLLAPSE_ARCSEC = 1.5
"""The angle sigma (arcsec) :attr:`CustodyRule.collapse_sigma_km` is stated for."""


@dataclass(frozen=True)
class CustodyRule:
    """When custody is lost, and whether it can be regained.

    Custody is lost at the first update step where the truth's log-likelihood under the belief's
    mixture (state in km and km/s) is below ``loglik_threshold``, or where the truth lies outside
    the ``hdr_threshold`` highest-density region for ``hdr_consecutive`` consecutive update steps,
    or where either is NaN (undefined: never counted as kept).
    A loss is final unless ``regain_updates`` > 0.
    """

    loglik_threshold: float = -100.0
    hdr_threshold: float = 0.997
    hdr_consecutive: int = 2
    precision_km: float = 100.0
    """A run that keeps custody is "tracking" only if its final largest per-axis position sigma
    is at most this (km); above it the cloud is consistent but too wide to be a track
    ("not-converged")."""
    collapse_sigma_km: float = 1e-3
    """A final largest per-axis position sigma below this (km, 1 m) is a collapsed belief: no
    telescope at 1.5 arcsec can pin a cislunar object that tightly ("diverged"). A run whose
    measurements are finer judges with it scaled by their finest angle sigma over 1.5 arcsec
    (:meth:`for_angle_sigma`)."""
    diverged_error_km: float = 50.0
    diverged_nees: float = 1e4
    """A final position error above ``diverged_error_km`` (km) together with a NEES above
    ``diverged_nees`` (error far beyond sigma: a 6-D chi-square exceeds 1e4 with probability
    ~0) is a diverged filter."""
    degenerate_ess: float = 7.0
    """A particle filter whose effective sample size (its ``ess_before_resampling`` diagnostic)
    or number of distinct particles (``unique_particles``) falls below this at any update has
    degenerate weights: fewer effective particles than the state dimension + 1 cannot even
    define a 6-D covariance ("diverged")."""
    max_earth_distance_km: float = 2e6
    """A final mean farther than this from Earth (km, ~5 lunar distances) has left cislunar
    space ("diverged")."""
    blowup_nis: float = 1e6
    blowup_nis_updates: int = 3
    """With or without a truth: an NIS above ``blowup_nis`` on ``blowup_nis_updates`` consecutive
    updates is a filter whose innovations blew up ("diverged" at the first of them: the step and
    time where it started). A consistent filter's NIS is chi-square with 2 to 6 degrees of
    freedom, above 40 with probability < 1e-6; 1e6 is a residual a thousand predicted sigmas away,
    beyond any outlier a real data set holds (100 arcsec at 0.5 arcsec is an NIS of 4e4)."""
    regain_updates: int = 0
    """After a loss, custody is regained once this many consecutive update steps find the truth
    inside the belief again (neither loss condition holds); 0 (the default): a loss is final. A
    target that maneuvers leaves any belief that does not know of the burn until the burn is
    detected and the filter widened (:mod:`cistrack.runs.maneuver_watch`): the maneuver scenarios
    judge custody through the burn by whether it is regained."""
    diverged_nis: float = 1e3
    diverged_nis_updates: int = 3
    """Without a truth: a median NIS above ``diverged_nis`` over the last ``diverged_nis_updates``
    updates means the measurements fall far outside the spread the belief predicts, the
    no-truth counterpart of "error far beyond sigma" ("diverged"; a chi-square with 2 to 6
    degrees of freedom exceeds 1e3 with probability ~0)."""

    def for_angle_sigma(self, arcsec: float) -> "CustodyRule":
        """This rule for measurements whose finest angle sigma is ``arcsec``: the collapse threshold
        scaled by ``arcsec`` / 1.5 when that is below 1 (a 1e-4 arcsec sensor pins the object to
        about a metre, and a consistent filter of it had been judged collapsed)."""
        from dataclasses import replace

        if not (np.isfinite(arcsec) and 0.0 < arcsec < COLLAPSE_ARCSEC):
            return self
        return replace(self, collapse_sigma_km=self.collapse_sigma_km * arcsec / COLLAPSE_ARCSEC)


@dataclass(frozen=True)
class Verdict:
    """The outcome of a run as judged by an observer.

    Attributes
    ----------
    kind : str                 during a run "kept", "lost" (truth left the belief) or
                               "filter-failed" (the filter raised); at the end of a run with a
                               truth :func:`cistrack.evaluation.verdicts.final_verdict` turns "kept" into
                               "tracking" or "not-converged" and any kind but "filter-failed"
                               into "diverged" when the belief collapsed or ran away; a run
                               without a truth ends "no-truth" (judged by its NIS instead); one
                               that did not finish (failed, interrupted) "none" unless custody
                               was lost before it stopped
    reason : str               one sentence a person can read, e.g. which threshold was crossed
    step : int or None         step index where the verdict changed from "kept" (None if kept)
    t_days : float or None     time of that step, days since the epoch
    """

    kind: str = "kept"
    reason: str = ""
    step: int | None = None
    t_days: float | None = None

    @property
    def kept(self) -> bool:
        """Custody kept: "kept" (during a run), "tracking" or "not-converged"."""
        return self.kind in KEPT_KINDS

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "Verdict":
        return cls(**{k: data.get(k) for k in ("kind", "reason", "step", "t_days")})


BACK_INSIDE_UPDATES: int = 2
"""Updates in a row with the truth inside the belief after a final loss before the verdict says so."""

_EARTH = np.array([-MU_EARTH_MOON, 0.0, 0.0])  # Earth in the synodic frame (LU)


class CustodyMetric(StepMetric):
    """Judges custody on every update step of a run with a truth (see the module docstring)."""

    name = "custody"
    needs = ("belief",)

    def __init__(self, rule: CustodyRule | None = None) -> None:
        self.rule = rule or CustodyRule()
        self.verdict = Verdict()
        self._hdr_run = 0
        self._inside_run = 0
        self._lost_reason: str | None = None
        self._back_from: tuple[int, float] = (0, 0.0)
        self.losses: list[tuple[Verdict, int, float]] = []
        """Each loss that was regained: (the loss's verdict, the step and time (days) it was regained)."""
        self.earth_distance_km: float | None = None
        """Distance of the last posterior mean from Earth (km), for the final verdict."""
        self.truth_earth_distance_km: float | None = None
        """Distance of the truth from Earth (km) at that step, when the run has a truth."""

    def judge(self, step) -> Verdict | None:
        """The verdict after update ``step`` if custody is lost there, else None."""
        m = step.metrics
        ll = m.get("truth_loglik", 0.0)
        if np.isnan(ll) or np.isnan(m.get("hdr_level", 0.0)):  # undefined: never counted as kept
            return Verdict("lost", f"the custody metrics are undefined (truth log-likelihood {ll:g}, HDR level "
                           f"{m.get('hdr_level', 0.0):g})", step.index, float(units.tu_to_days(step.t)))
        if ll < self.rule.loglik_threshold:  # a collapsed cloud gives about -1e38: 3 digits, not 40
            shown = f"{ll:.1f}" if ll > -1e6 else f"{ll:.3g}"
            return Verdict("lost", f"truth log-likelihood {shown} < {self.rule.loglik_threshold:g}",
                           step.index, float(units.tu_to_days(step.t)))
        self._hdr_run = self._hdr_run + 1 if m.get("hdr_level", 0.0) > self.rule.hdr_threshold else 0
        if self._hdr_run >= self.rule.hdr_consecutive:
            return Verdict("lost", f"truth outside the {self.rule.hdr_threshold:g} highest-density region "
                           f"on {self._hdr_run} consecutive updates", step.index, float(units.tu_to_days(step.t)))
        return None

    def _track_mean(self, step) -> None:
        belief = getattr(step, "belief", None)
        if belief is None:
            return
        mean = np.asarray(belief.mixture.mean, dtype=float)
        self.earth_distance_km = float(np.linalg.norm(mean[:3] - _EARTH) * units.LU_KM)
        truth = getattr(step, "truth", None)
        self.truth_earth_distance_km = (None if truth is None else
                                        float(np.linalg.norm(np.asarray(truth, dtype=float)[:3] - _EARTH) * units.LU_KM))

    def compute(self, run, step, event: str) -> dict[str, float]:
        """``{"custody": 1.0 or 0.0}`` on every table step of a run with a truth (none without):
        the verdict after judging ``step`` when it is a posterior; the prior of an update is not judged."""
        if event == "updated" and step.truth is not None:
            if self.verdict.kept:
                lost = self.judge(step)
                if lost is not None:
                    self.verdict, self._inside_run = lost, 0
            elif self.verdict.kind == "lost" and self.rule.regain_updates > 0:
                self._regain(step)
            elif self.verdict.kind == "lost":
                self._watch_back(step)
        elif step.kind not in ("initial", "predict"):
            return {}
        self._track_mean(step)
        return {} if step.truth is None else {"custody": 1.0 if self.verdict.kept else 0.0}

    def _regain(self, step) -> None:
        """Count ``step`` towards regaining custody; regained after ``rule.regain_updates`` in a row."""
        self._inside_run = self._inside_run + 1 if self.judge(step) is None else 0
        if self._inside_run < self.rule.regain_updates:
            return
        t = float(units.tu_to_days(step.t))
        self.losses.append((self.verdict, step.index, t))
        said = "; ".join(f"custody lost at step {v.step} (t = {v.t_days:.3f} d: {v.reason}) and regained at step "
                         f"{k} (t = {tk:.3f} d)" for v, k, tk in self.losses)
        self.verdict, self._inside_run, self._hdr_run = Verdict("kept", said), 0, 0

    def _watch_back(self, step) -> None:
        """After a final loss, say in the verdict when the truth has been back inside the belief on
        every update since some step (the loss stands: ``rule.regain_updates`` is 0)."""
        if self._lost_reason is None:
            self._lost_reason = self.verdict.reason
        inside = self.judge(step) is None
        self._inside_run = self._inside_run + 1 if inside else 0
        if self._inside_run == 1:
            self._back_from = (step.index, float(units.tu_to_days(step.t)))
        note = ""
        if self._inside_run >= BACK_INSIDE_UPDATES:
            k, t = self._back_from
            note = (f"; the truth is back inside the belief on every update since step {k} (t = {t:.3f} d, "
                    f"{self._inside_run} updates), but a loss is final with [custody] regain_updates = 0")
        self.verdict = Verdict("lost", self._lost_reason + note, self.verdict.step, self.verdict.t_days)

    @hookimpl
    def cistrack_run_failed(self, run, step_index, error) -> None:
        if self.verdict.kept:
            self.verdict = Verdict("filter-failed", str(error), step_index, None)


__getattr__ = renamed_names(__name__, {"CustodyObserver": ("CustodyMetric", CustodyMetric)})  # the old name, for one release
