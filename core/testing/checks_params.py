"""Checks every component kind shares: the constructor-parameter conventions and pickling."""
from __future__ import annotations

import inspect
import math
import types
import typing
from typing import Any

from cistrack.interfaces.component import param_specs
from cistrack.errors import ParameterError
from cistrack.testing.check_support import describe_exception, params_equal, require, round_trip

__all__ = ["check_parameters_declared", "check_get_params_returns_constructor_values",
           "check_clone_from_params", "check_bad_parameters_raise_parameter_error",
           "check_picklable", "PARAMETER_CHECKS"]


def _specs(component: Any):
    return param_specs(type(component))


def check_parameters_declared(component: Any) -> None:
    """Every constructor parameter is keyword-usable, has a type hint and a default."""
    init = type(component).__init__
    params = list(inspect.signature(init).parameters.values())[1:]
    for p in params:
        require(p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD),
                f"__init__ takes {'*' if p.kind is p.VAR_POSITIONAL else '**'}{p.name}: declare every parameter by name "
                "so scenario files can be validated")
        require(p.kind != p.POSITIONAL_ONLY, f"parameter '{p.name}' is positional-only; parameters are passed by keyword")
    for name, spec in _specs(component).items():
        require(not spec.required, f"parameter '{name}' has no default; every parameter needs one")
        require(spec.annotation is not Any, f"parameter '{name}' has no type hint")


def check_get_params_returns_constructor_values(component: Any) -> None:
    """Each parameter is stored under an attribute of the same name; ``get_params`` and repr work."""
    for name in _specs(component):
        require(hasattr(component, name),
                f"parameter '{name}' is not stored as attribute self.{name} (get_params() reads it from there)")
    require(callable(getattr(component, "get_params", None)), "no get_params(); derive from cistrack.interfaces.component.Component")
    params = component.get_params()
    require(set(params) == set(_specs(component)),
            f"get_params() returned {sorted(params)} but the constructor takes {sorted(_specs(component))}")
    repr(component)


def check_clone_from_params(component: Any) -> None:
    """``type(c)(**c.get_params())`` builds an equal component (how studies rebuild it)."""
    params = component.get_params()
    try:
        other = type(component)(**params)
    except Exception as exc:
        require(False, f"rebuilding from get_params() failed: {describe_exception(exc)}; store parameters in a form "
                       "the constructor accepts again")
    require(params_equal(other.get_params(), params),
            f"rebuilding from get_params() changed the parameters: {params} -> {other.get_params()}")


def _annotation_types(ann: Any) -> set:
    origin = typing.get_origin(ann)
    if origin is typing.Union or (hasattr(types, "UnionType") and origin is types.UnionType):
        out: set = set()
        for a in typing.get_args(ann):
            out |= _annotation_types(a)
        return out
    return {ann}


def _bad_values(ann: Any) -> list[tuple[Any, str]]:
    kinds = _annotation_types(ann)
    bad: list[tuple[Any, str]] = []
    if bool in kinds:
        return bad
    if (float in kinds or int in kinds) and str not in kinds:
        bad.append(("not-a-number", "a string for a numeric parameter"))
    if float in kinds:
        bad.append((math.nan, "NaN"))
    elif int in kinds:
        bad.append((2.5, "a non-integer for an integer parameter"))
    return bad


def check_bad_parameters_raise_parameter_error(component: Any) -> None:
    """A wrong-typed or NaN numeric parameter raises ParameterError naming the parameter."""
    cls = type(component)
    base = component.get_params()
    for name, spec in _specs(component).items():
        for value, what in _bad_values(spec.annotation):
            params = dict(base)
            params[name] = value
            try:
                cls(**params)
            except ParameterError as exc:
                require(name in str(exc), f"{cls.__name__}({name}={value!r}) raised ParameterError, but its message "
                                          f"does not name the parameter '{name}': {exc}")
                continue
            except Exception as exc:
                require(False, f"{cls.__name__}({name}={value!r}) ({what}) raised {describe_exception(exc)} instead of "
                               "cistrack.errors.ParameterError; validate with cistrack.interfaces.component.check_*")
            require(False, f"{cls.__name__}({name}={value!r}) ({what}) was accepted; validate '{name}' in __init__ "
                           "with cistrack.interfaces.component.check_positive/check_range/check_int")


def check_picklable(component: Any) -> None:
    """The component survives pickle with the same parameters."""
    other = round_trip(component)
    require(type(other) is type(component), "unpickling gave a different type")
    if callable(getattr(component, "get_params", None)):
        require(params_equal(other.get_params(), component.get_params()), "unpickling changed the parameters")


PARAMETER_CHECKS = [
    ("parameters_declared", check_parameters_declared),
    ("get_params_returns_constructor_values", check_get_params_returns_constructor_values),
    ("clone_from_params", check_clone_from_params),
    ("bad_parameters_raise_parameter_error", check_bad_parameters_raise_parameter_error),
    ("picklable", check_picklable),
]
