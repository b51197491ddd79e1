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
"""
from __future__ import annotations

import inspect
import sys
from typing import Any, TypeVar

__all__ = ["preset", "preset_defaults"]

C = TypeVar("C", bound=type)


def preset(base: C, name: str, summary: str, **defaults: Any) -> C:
    """A subclass of ``base`` named ``name`` whose constructor defaults are ``defaults``.

    ``summary`` is its docstring (the first paragraph is what ``cistrack plugins`` lists).
    ``defaults`` must name parameters of ``base``'s constructor (a TypeError names any other);
    values are validated by ``base`` when an instance is built.
    """
    init = base.__init__
    signature = inspect.signature(init)
    params = list(signature.parameters.values())
    unknown = sorted(set(defaults) - {p.name for p in params[1:]})
    if unknown:
        raise TypeError(f"preset {name!r}: {base.__name__} has no parameters {unknown}; it takes "
                        f"{', '.join(p.name for p in params[1:])}")
    own = [params[0]] + [p.replace(kind=inspect.Parameter.KEYWORD_ONLY, default=defaults.get(p.name, p.default))
                         for p in params[1:]]

    def __init__(self, **params: Any) -> None:
        init(self, **{**defaults, **params})

    __init__.__signature__ = signature.replace(parameters=own)  # type: ignore[attr-defined]
    __init__.__annotations__ = dict(getattr(init, "__annotations__", {}))
    __init__.__wrapped__ = init  # type: ignore[attr-defined]  # get_type_hints resolves base's names
    module = sys._getframe(1).f_globals.get("__name__", base.__module__)
    cls = type(base)(name, (base,), {"__init__": __init__, "__doc__": summary, "__module__": module,
                                      "__qualname__": name, "_preset_defaults": dict(defaults)})
    __init__.__qualname__ = f"{name}.__init__"
    return cls


def preset_defaults(cls: type) -> dict[str, Any]:
    """The defaults a preset sets over its base (an empty dict for a class that is no preset)."""
    return dict(cls.__dict__.get("_preset_defaults", {}))
