"""bench_stage_cost writes its literal-coefficient variant from the model's own source."""
from __future__ import annotations

import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "benchmarks"))

from bench_stage_cost import literal_coefficients  # noqa: E402


def test_the_literal_variant_is_written_from_the_current_ephemeris_source(tmp_path):
    module = literal_coefficients(str(tmp_path), record=3)
    from cistrack.plugins.dynamics.ephemeris import EphemerisDynamics

    model = EphemerisDynamics(epoch="2026-01-01T00:00:00Z")
    model._ensure_window(0.0, 1.0)
    out = np.empty(6)
    module.literal_coefficients_rhs.py_func(0.5, np.array([0.3, 0.2, 0.1, 0.0, 0.5, 0.0]), model._params(), out)
    assert module.FIXED_RECORD == 3
    assert np.all(np.isfinite(out))
