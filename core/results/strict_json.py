"""Strict JSON numbers: what cistrack writes as JSON (manifests, ``fit.json``) has no NaN or
infinity, which Python's json module writes by default but JSON itself, jq and JavaScript do not
have; such a number is written as null."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["finite_or_null"]


def finite_or_null(v: Any) -> Any:
    """``v`` with every NaN or infinite number (Python or numpy, in lists and tables) as None."""
    if isinstance(v, dict):
        return {k: finite_or_null(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [finite_or_null(x) for x in v]
    if isinstance(v, np.ndarray):
        return finite_or_null(v.tolist())
    if isinstance(v, (float, np.floating)) and not math.isfinite(float(v)):
        return None
    return v
