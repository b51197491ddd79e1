"""Presets: a registered component that is another one with other defaults, declared in a few lines.

``pgm-paper`` is the PGM with the paper's settings, not a second constructor that restates 24
parameters: ::

    PaperPGMFilter = preset(PGMFilter, "PaperPGMFilter", "The paper's plain PGM ...",
                            component_update="ensemble", reanchor="off", ...)
    registry.add("filter", "pgm-paper", PaperPGMFilter)

The preset is a subclass of the base whose constructor takes the same parameters (keyword only),
with the given defaults in its signature, so ``cistrack plugins pgm-paper``, docs/components.md
and a scenario's validation see the preset's own defaults; the meanings of the parameters are the
base's. Assign the preset to a module-level name equal to ``name``: its instances then pickle
like any component's.

A preset may also fix a component-valued parameter of the base to a component built from the
preset's own parameters (``nested``): the IOD preset "noisy-range" is kinematic-fit with
``range_prior`` fixed to ``NoisyRange(alpha=alpha)`` and ``alpha`` a parameter of the preset ::

    NoisyRangeIOD = preset(KinematicFitIOD, "NoisyRangeIOD", "...", nested={"range_prior": (NoisyRange, ("alpha",))})
"""
from __future__ import annotations

import inspect
import sys
from typing import Any, TypeVar

from cistrack.errors import ParameterError

__all__ = ["preset", "preset_defaults"]

C = TypeVar("C", bound=type)
_KW = inspect.Parameter.KEYWORD_ONLY


def preset(base: C, name: str, summary: str, *, nested: dict[str, tuple[type, tuple[str, ...]]] | None = None,
           fixed: dict[str, Any] | None = None, **defaults: Any) -> C:
    """A subclass of ``base`` named ``name`` whose constructor defaults are ``defaults``.

    ``summary`` is its docstring (the first paragraph is what ``cistrack plugins`` lists).
    ``nested`` maps a parameter of ``base`` to ``(cls, names)``: that parameter is no longer one of
    the preset's, it is always ``cls(**{n: value of n})``; each of ``names`` is a parameter of
    ``base`` (whose value goes to both) or else becomes a parameter of the preset, with ``cls``'s
    annotation, default and documented meaning, stored on the instance as the built component
    holds it. ``fixed`` maps parameters of ``base`` to values the preset always passes (they are not
    the preset's parameters). ``defaults`` must name the preset's parameters (a TypeError names any
    other); values are validated when an instance is built.
    """
    nested, fixed = dict(nested or {}), dict(fixed or {})
    init: Any = getattr(base, "__init__")
    signature = inspect.signature(init)
    base_params = {p.name: p for p in list(signature.parameters.values())[1:]}
    extra = _nested_parameters(nested, base_params)
    if set(fixed) - set(base_params):
        raise TypeError(f"preset {name!r}: fixed names no parameter of {base.__name__}: {sorted(set(fixed) - set(base_params))}")
    params = {n: p for n, p in base_params.items() if n not in nested and n not in fixed} | extra
    unknown = sorted(set(defaults) - set(params))
    if unknown:
        raise TypeError(f"preset {name!r}: {base.__name__} has no parameters {unknown}; it takes "
                        f"{', '.join(params)}")
    own = [p.replace(kind=_KW, default=defaults.get(n, p.default)) for n, p in params.items()]
    full = {p.name: p.default for p in own}

    def __init__(self, **given: Any) -> None:
        values = {**full, **given}
        if set(given) & set(fixed):  # not a parameter of the preset: refused as the base refuses unknown ones
            raise TypeError(f"{name}() got fixed parameters {sorted(set(given) & set(fixed))}")
        kept = {n: values.pop(n) for n in extra if n in values}
        for param, (cls, names) in nested.items():
            values[param] = _build_nested(self, cls, {n: kept[n] if n in kept else values[n] for n in names})
        init(self, **values, **fixed)
        for n in kept:
            setattr(self, n, getattr(next(values[p] for p, (_, ns) in nested.items() if n in ns), n))

    setattr(__init__, "__signature__", signature.replace(parameters=[list(signature.parameters.values())[0], *own]))
    __init__.__annotations__ = {**getattr(init, "__annotations__", {}), **{n: p.annotation for n, p in extra.items()}}
    setattr(__init__, "__wrapped__", init)  # get_type_hints resolves the base's names
    module = sys._getframe(1).f_globals.get("__name__", base.__module__)
    doc = summary + _parameters_section(nested, extra)
    cls = type(base)(name, (base,), {"__init__": __init__, "__doc__": doc, "__module__": module,
                                      "__qualname__": name, "_preset_defaults": {**fixed, **defaults}})
    __init__.__qualname__ = f"{name}.__init__"
    return cls


def preset_defaults(cls: type) -> dict[str, Any]:
    """The defaults a preset sets over its base (an empty dict for a class that is no preset)."""
    return dict(cls.__dict__.get("_preset_defaults", {}))


def _nested_parameters(nested: dict[str, tuple[type, tuple[str, ...]]],
                       base_params: dict[str, inspect.Parameter]) -> dict[str, inspect.Parameter]:
    """The preset's own parameters taken from the nested components' constructors."""
    out: dict[str, inspect.Parameter] = {}
    for param, (cls, names) in nested.items():
        if param not in base_params:
            raise TypeError(f"nested: the base has no parameter {param!r}")
        theirs = dict(inspect.signature(cls).parameters)
        for n in names:
            if n not in base_params and n not in theirs:
                raise TypeError(f"nested: {cls.__name__} has no parameter {n!r}")
            if n not in base_params:
                out[n] = theirs[n]
    return out


def _build_nested(owner: Any, cls: type, values: dict[str, Any]) -> Any:
    """``cls(**values)``; a ParameterError names the preset instead of the nested component."""
    try:
        return cls(**values)
    except ParameterError as exc:
        label = cls._label() if hasattr(cls, "_label") else cls.__name__
        raise ParameterError(str(exc).replace(label, owner._label())) from None


def _parameters_section(nested: dict[str, tuple[type, tuple[str, ...]]], extra: dict[str, inspect.Parameter]) -> str:
    """A numpydoc Parameters section for the preset's own parameters, from the nested classes' docs."""
    if not extra:
        return ""
    lines = ["", "", "Parameters", "----------"]
    for cls, names in nested.values():
        doc = inspect.cleandoc(cls.__doc__ or "").splitlines()
        for n in names:
            if n in extra:
                lines += [next((ln for ln in doc if ln.split(":")[0].strip() == n and " : " in ln), f"{n} : any"),
                          *(f"    {ln}" for ln in _meaning(doc, n))]
    return "\n".join(lines)


def _meaning(doc: list[str], name: str) -> list[str]:
    """The indented lines under ``name : type`` in a cleaned docstring."""
    for i, line in enumerate(doc):
        if not line.startswith((" ", "\t")) and " : " in line and line.split(":")[0].strip() == name:
            out = []
            for body in doc[i + 1:]:
                if not body.startswith((" ", "\t")):
                    break
                out.append(body.strip())
            return out
    return []
