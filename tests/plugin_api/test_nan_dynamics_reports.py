"""The conformance suite says a dynamics model returned NaN or infinite states when it did, and
checks the transition matrices ``cistrack fit`` uses: a model turning NaN after a few calls had
been told only to "control the error of each particle separately", and one whose transition
matrices are NaN passed every check."""
from __future__ import annotations

import numpy as np

from cistrack.interfaces.dynamics import Propagation
from cistrack.testing import ConformanceError, ReferenceCR3BP, check_plugin


class NanAfterThreeCalls(ReferenceCR3BP):
    """The reference CR3BP whose fourth and later propagations are NaN."""

    def propagate(self, states, t0, times):
        self._calls = getattr(self, "_calls", 0) + 1
        p = super().propagate(states, t0, times)
        if self._calls <= 3:
            return p
        return Propagation(p.times, p.states * np.nan, p.alive, p.impact_body, p.impact_time)


class NanTransitionMatrices(ReferenceCR3BP):
    """The reference CR3BP whose transition matrices are NaN."""

    def propagate_with_stm(self, state, t0, times):
        states, stms = super().propagate_with_stm(state, t0, times)
        return states, stms * np.nan


def _failed(cls) -> dict[str, str]:
    try:
        check_plugin(cls)
    except ConformanceError as err:
        return {r.name: r.message for r in err.results if not r.passed}
    return {}


def test_nan_states_are_reported_as_nan_not_as_a_difference_between_particles():
    why = _failed(NanAfterThreeCalls)["propagate_vectorised_matches_loop"]
    assert "propagate() returned NaN or infinite states" in why and "differs" not in why


def test_nan_transition_matrices_fail_their_check():
    failed = _failed(NanTransitionMatrices)
    assert list(failed) == ["transition_matrices_finite"]
    assert failed["transition_matrices_finite"].endswith("propagate_with_stm returned NaN or infinite states or "
                                                         "transition matrices on the 9:2 NRHO over 6 hours")
