"""Outcomes of conformance checks: one result per check, a report, and the error raised."""
from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["CheckResult", "ConformanceReport", "ConformanceError"]


class ConformanceError(AssertionError):
    """A component failed a conformance check. The message names the check and why.

    ``results`` holds every :class:`CheckResult` of the run that raised it (empty when a single
    check raised it directly).
    """

    def __init__(self, message: str, results: list["CheckResult"] | None = None):
        super().__init__(message)
        self.results = list(results or [])


@dataclass(frozen=True)
class CheckResult:
    """One check: its name, whether it passed, and why not (empty when it passed)."""

    name: str
    passed: bool
    message: str = ""
    seconds: float = 0.0

    def __str__(self) -> str:
        status = "PASS" if self.passed else "FAIL"
        return f"{status} {self.name}" + (f": {self.message}" if self.message else "")


@dataclass
class ConformanceReport:
    """Every check run on one component. ``bool(report)`` is True when all passed."""

    component: str
    kind: str
    results: list[CheckResult] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)

    @property
    def failures(self) -> list[CheckResult]:
        return [r for r in self.results if not r.passed]

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        head = (f"{self.kind} {self.component}: {len(self.results) - len(self.failures)}/"
                f"{len(self.results)} checks passed")
        return "\n".join([head] + [f"  {r}" for r in self.results])
