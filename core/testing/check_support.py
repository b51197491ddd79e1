"""What the checks share: failing with a reason, fresh instances, comparisons, guards."""
from __future__ import annotations

import copy
import pickle
import random
from contextlib import contextmanager
from typing import Any

import numpy as np

from cistrack.testing.check_results import ConformanceError

__all__ = ["require", "fresh", "params_equal", "no_global_random_state", "unchanged",
           "round_trip", "close", "describe_exception"]


def require(condition: Any, why: str) -> None:
    """Fail the running check with ``why`` unless ``condition`` holds."""
    if not condition:
        raise ConformanceError(why)


def fresh(component: Any) -> Any:
    """A new instance with the same parameters (scikit-learn's ``clone``); classes are built
    with their defaults; objects without parameters are deep-copied."""
    if isinstance(component, type):
        return component()
    get_params = getattr(component, "get_params", None)
    if callable(get_params):
        return type(component)(**get_params())
    return copy.deepcopy(component)


def params_equal(a: dict, b: dict) -> bool:
    """Parameter dicts equal, comparing arrays element-wise and nested components (such as a
    sensor's dynamics model) by type and parameters."""
    if set(a) != set(b):
        return False
    for k in a:
        x, y = a[k], b[k]
        if callable(getattr(x, "get_params", None)) and type(x) is type(y) and x is not y:
            if not params_equal(x.get_params(), y.get_params()):
                return False
        elif isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            if not np.array_equal(np.asarray(x), np.asarray(y)):
                return False
        elif x != y and not (isinstance(x, float) and isinstance(y, float) and np.isnan(x) and np.isnan(y)):
            return False
    return True


@contextmanager
def no_global_random_state(what: str):
    """Fail if the block draws from numpy's legacy global generator or Python's ``random``."""
    np_state = np.random.get_state()
    py_state = random.getstate()
    try:
        yield
    finally:
        np_after = np.random.get_state()
        py_after = random.getstate()
    same_np = np_state[0] == np_after[0] and np.array_equal(np_state[1], np_after[1]) and np_state[2:] == np_after[2:]
    require(same_np, f"{what} drew from numpy's global random state (np.random.*); use the Generator passed in")
    require(py_state == py_after, f"{what} drew from Python's global 'random' module; use the Generator passed in")


class _Snapshot:
    def __init__(self, name: str, value: Any):
        self.name = name
        self.value = value
        self.copy = copy.deepcopy(value)


def _deep_equal(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.shape == b.shape and np.array_equal(a, b, equal_nan=True)
    if hasattr(a, "__dict__") and not isinstance(a, type):
        return type(a) is type(b) and _deep_equal(vars(a), vars(b))
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_deep_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return type(a) is type(b) and len(a) == len(b) and all(_deep_equal(x, y) for x, y in zip(a, b))
    try:
        return bool(a == b)
    except Exception:
        return True


@contextmanager
def unchanged(**inputs: Any):
    """Fail if the block modifies any of ``inputs`` (arrays, belief or measurement objects)."""
    snaps = [_Snapshot(k, v) for k, v in inputs.items()]
    yield
    for s in snaps:
        require(_deep_equal(s.value, s.copy), f"the input '{s.name}' was modified in place; copy it before changing it")


def round_trip(component: Any) -> Any:
    """``component`` pickled and unpickled (studies run components in other processes)."""
    try:
        data = pickle.dumps(component)
    except Exception as exc:
        raise ConformanceError(f"pickle.dumps failed: {describe_exception(exc)}; keep only picklable "
                               "attributes (no lambdas, open files or compiled handles; rebuild them lazily)") from exc
    return pickle.loads(data)


def close(a: np.ndarray, b: np.ndarray, rtol: float, atol: float) -> tuple[bool, float]:
    """Whether ``a`` and ``b`` agree, and the largest absolute difference."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    if a.shape != b.shape:
        return False, float("inf")
    diff = float(np.max(np.abs(a - b))) if a.size else 0.0
    return bool(np.allclose(a, b, rtol=rtol, atol=atol)), diff


def describe_exception(exc: BaseException) -> str:
    """``RuntimeError: boom``; for ``sys.exit``: ``SystemExit: it called sys.exit(7)``; the type
    alone when the message is empty (``GeneratorExit``)."""
    from cistrack.errors import exception_text

    return exception_text(exc)
