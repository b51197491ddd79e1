"""The base of every plugin component: constructor parameters only, scikit-learn style.

A component declares its parameters as keyword arguments of ``__init__`` with type hints and
defaults, stores each under the same attribute name, and checks values in ``__init__`` with the
``check_*`` helpers below, which raise :class:`~cistrack.errors.ParameterError` naming the
component, the parameter, the value and what is allowed. Scenario files are validated against
the same signature before anything runs (see :mod:`cistrack.scenario.loading`).
"""
from __future__ import annotations

import inspect
from abc import ABC
import math
import numbers
import typing
from dataclasses import dataclass
from typing import Any, ClassVar

from cistrack.errors import ParameterError, quoted

__all__ = [
    "Component", "component_name", "ParamSpec", "param_specs", "MemoryNeed", "BYTES_PER_PARTICLE", "IOD_CHUNK_BYTES",
    "check_positive", "check_nonnegative", "check_range", "check_choice", "check_int",
    "SIGMA_ARCSEC_BOUNDS", "sigma_arcsec_problem", "check_sigma_arcsec",
]

_EMPTY = inspect.Parameter.empty

BYTES_PER_PARTICLE = 446
"""Memory per particle of a run, used only to refuse sizes that cannot fit before allocating.
Measured: a whole one-period Example 1 run (IOD + PGM) peaked 386 MiB above the process's start at
1,000,000 particles, 405 bytes per particle (``benchmarks/bench_memory.py --sizes 100000 300000
1000000 --cases run``, docs/performance.md); rounded up by 10 %. The peak is the PGM's update of
the ``reacquire_factor`` (4) x ``n_particles`` particles it draws after the IOD, in chunks
(:mod:`cistrack.plugins.filters.pgm.reacquisition_particles`). The IOD fits its oversampled
samples in chunks of fixed size (:data:`IOD_CHUNK_BYTES`), so the oversampling factor does not
multiply it."""
IOD_CHUNK_BYTES = 256 * 2 ** 20
"""Work arrays of one IOD chunk (measured ~130 MiB for 131,072 samples of 12 measurements)."""


@dataclass(frozen=True)
class MemoryNeed:
    """What a component will hold in memory during a run, and the parameter that sets it.

    A scenario asks every component for it (:meth:`Component.memory_need`) and refuses, before
    anything is allocated, a need larger than the memory available, naming ``parameter``."""

    bytes: float
    """Bytes, estimated."""
    parameter: str
    """The constructor parameter that sets the need (``"n_particles"``)."""
    value: float
    """Its value."""
    what: str
    """What needs the memory, for the message (``"1e+07 particles"``)."""

    @classmethod
    def particles(cls, n: int, extra_bytes: float = 0.0) -> "MemoryNeed":
        """``n`` particles at :data:`BYTES_PER_PARTICLE` each, plus ``extra_bytes``."""
        return cls(n * BYTES_PER_PARTICLE + extra_bytes, "n_particles", float(n), f"{n:.3g} particles")


@dataclass(frozen=True)
class ParamSpec:
    """One constructor parameter: its name, type annotation, default and doc line."""

    name: str
    annotation: Any
    default: Any
    required: bool


def param_specs(cls: type) -> dict[str, ParamSpec]:
    """Parameters of ``cls.__init__`` (keyword parameters after ``self``), in order."""
    init: Any = getattr(cls, "__init__")  # the class's own or inherited constructor (not bound)
    if init is object.__init__:
        return {}
    try:
        hints = typing.get_type_hints(init)
    except Exception:  # unresolved forward references: fall back to raw annotations
        hints = {}
    out: dict[str, ParamSpec] = {}
    for p in list(inspect.signature(init).parameters.values())[1:]:
        if p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
            continue
        ann = hints.get(p.name, p.annotation if p.annotation is not _EMPTY else Any)
        out[p.name] = ParamSpec(p.name, ann, p.default if p.default is not _EMPTY else None,
                                p.default is _EMPTY)
    return out



def component_name(obj: Any) -> str:
    """The name a component goes by in messages: its registered name, else its class's name (a
    component made by hand, or an object that is none)."""
    return getattr(obj, "registry_name", None) or type(obj).__name__

class Component(ABC):
    """Base class of every registered component (an ABC: a subclass that leaves one of its
    interface's ``@abstractmethod`` methods unimplemented cannot be constructed).

    Subclasses set ``kind`` (done by the kind's interface class). The registry sets
    ``registry_name`` on the class it registers, so error messages can name the plugin.
    """

    kind: ClassVar[str] = ""
    nested_params: ClassVar[dict[str, tuple[str, ...]]] = {}
    """Parameters handed on to a nested component when a scenario builds it: parameter holding
    the nested component -> names of this component's parameters that the nested one takes too
    (e.g. the PGM's ``{"clusterer": ("n_components",)}``). A nested table that sets the
    parameter itself keeps its own value. So the nested component is built once, already with
    the value, instead of being copied to change it."""
    registry_name: ClassVar[str] = ""

    @classmethod
    def _label(cls) -> str:
        return f"{cls.kind or 'component'} '{cls.registry_name or cls.__name__}'"

    def memory_need(self) -> MemoryNeed | None:
        """The memory this component will hold during a run (:class:`MemoryNeed`), or None when it
        is small. Particle filters and IOD methods override it."""
        return None

    def get_params(self) -> dict[str, Any]:
        """The constructor parameters and their current values (scikit-learn's contract)."""
        return {name: getattr(self, name) for name in param_specs(type(self))}

    def __repr__(self) -> str:
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"

    # -- validation helpers usable as self.check_xxx in __init__ ---------------------------------
    def _fail(self, name: str, value: Any, allowed: str) -> None:
        raise ParameterError(f"{self._label()}: parameter '{name}' = {quoted(value)} is invalid: {allowed}")


def _invalid(owner: Component | None, name: str, value: Any, allowed: str) -> None:
    """The ParameterError of ``owner``'s parameter ``name`` (one naming the parameter alone when a
    check is called with no component, e.g. ``check_int(None, "n", v)``)."""
    if owner is not None and hasattr(owner, "_fail"):
        owner._fail(name, value, allowed)
    raise ParameterError(f"parameter '{name}' = {quoted(value)} is invalid: {allowed}")


def _real(owner: Component, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):  # numpy's scalars are Real
        _invalid(owner, name, value, "must be a number")
    v = float(value)
    if not math.isfinite(v):
        _invalid(owner, name, value, "must be finite")
    return v


def check_positive(owner: Component, name: str, value: Any) -> float:
    """Return ``value`` as float; raise ParameterError unless it is finite and > 0."""
    v = _real(owner, name, value)
    if v <= 0:
        _invalid(owner, name, value, "must be > 0")
    return v


SIGMA_ARCSEC_BOUNDS = (1e-6, 648000.0)
"""The angle sigmas (arcsec) a measurement may have: from a micro-arcsecond (beyond any telescope's
astrometry) to 180 degrees (an angle that says nothing). A sigma outside them is a unit or a typing
mistake, not a measurement: weights of 1e60 or 1e-600 wreck the fits that use them."""


def sigma_arcsec_problem(value: float) -> str | None:
    """Why an angle sigma of ``value`` arcsec is not one a measurement can have, or None."""
    lo, hi = SIGMA_ARCSEC_BOUNDS
    if not (math.isfinite(value) and lo <= value <= hi):
        return f"must lie in [{lo:g}, {hi:g}] arcsec (a micro-arcsecond to 180 degrees)"
    return None


def check_sigma_arcsec(owner: Component, name: str, value: Any) -> float:
    """Return ``value`` (an angle sigma, arcsec) as float; raise ParameterError unless it lies in
    :data:`SIGMA_ARCSEC_BOUNDS`."""
    v = _real(owner, name, value)
    problem = sigma_arcsec_problem(v)
    if problem:
        _invalid(owner, name, value, problem)
    return v


def check_nonnegative(owner: Component, name: str, value: Any) -> float:
    """Return ``value`` as float; raise ParameterError unless it is finite and >= 0."""
    v = _real(owner, name, value)
    if v < 0:
        _invalid(owner, name, value, "must be >= 0")
    return v


def check_range(owner: Component, name: str, value: Any, lo: float, hi: float,
                *, lo_open: bool = False, hi_open: bool = False) -> float:
    """Return ``value`` as float; raise ParameterError unless lo <= value <= hi (or open ends)."""
    if math.isnan(lo) or math.isnan(hi):  # every comparison with NaN is false: nothing would be refused
        raise ValueError(f"check_range for '{name}': the bounds must be numbers, got {lo!r} and {hi!r}")
    v = _real(owner, name, value)
    bad = (v < lo or v > hi or (lo_open and v == lo) or (hi_open and v == hi))
    if bad:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        _invalid(owner, name, value, f"must lie in {left}{lo}, {hi}{right}")
    return v


def check_int(owner: Component, name: str, value: Any, minimum: int | None = None,
              maximum: int | None = None) -> int:
    """Return ``value`` as int; raise ParameterError unless it is an integer within bounds."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):  # numpy's integers are Integral
        if isinstance(value, numbers.Real) and not isinstance(value, bool) and float(value).is_integer():
            value = int(float(value))
        else:
            _invalid(owner, name, value, "must be an integer")
    if minimum is not None and value < minimum:
        _invalid(owner, name, value, f"must be >= {minimum}")
    if maximum is not None and value > maximum:
        _invalid(owner, name, value, f"must be <= {maximum}")
    return int(value)


def check_choice(owner: Component, name: str, value: Any, choices: typing.Iterable[str]) -> str:
    """Return ``value``; raise ParameterError unless it is one of ``choices`` (one string is one
    choice, not its letters)."""
    choices = [choices] if isinstance(choices, str) else list(choices)
    if value not in choices:
        _invalid(owner, name, value, f"must be one of {', '.join(map(repr, choices))}")
    return value
