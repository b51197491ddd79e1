"""The PGM's steps given by name or as components: checking a name, and building the step.

A step parameter (``component_update``, ``posterior_draw``, ``reanchor``) holds a component of its
kind (:mod:`cistrack.interfaces.pgm_steps`) or a registered name of that kind. In a scenario the
name arrives built, through the run's registry, with the PGM's own settings that the step takes
(``PGMFilter.nested_params``); a name given in Python is built here. The rule for those settings:
a step left at its class default takes the PGM's value (on a copy); a step's own value stands
while the PGM's is at the PGM's default (a step table in a scenario sets its own values); set
differently in both places, it is refused (set it in one place).
"""
from __future__ import annotations

from typing import Any

from cistrack.errors import ParameterError, UnknownComponentError
from cistrack.interfaces.component import Component, param_specs

__all__ = ["check_step", "resolve_step"]


def check_step(owner: Component, name: str, value: Any, interface: type, builtins: tuple[str, ...]) -> Any:
    """``value`` if it is an ``interface`` component, a built-in name or a registered name of the
    interface's kind; else the owner's ParameterError naming ``name`` and what is allowed."""
    if isinstance(value, interface) or (isinstance(value, str) and value in builtins):
        return value
    kind = interface.kind
    if isinstance(value, str):
        from cistrack.api import default_registry

        if (kind, value) in default_registry():
            return value
        owner._fail(name, value, f"must be a {kind} component or one of the registered names "
                                 f"{', '.join(default_registry().names(kind))}")
    owner._fail(name, value, f"must be a {interface.__name__} ({kind} component) or a registered {kind} name")


def resolve_step(kind: str, value: Component | str, handed: dict[str, Any], who: str,
                 owner_defaults: dict[str, Any] | None = None, registry=None) -> Component:
    """The step ``value`` as a component, with the PGM's settings ``handed`` (name -> value) where
    it takes them (``owner_defaults``: the PGM's defaults of those settings). A name is created
    through ``registry`` (default: the installed plugins)."""
    if isinstance(value, str):
        if registry is None:
            from cistrack.api import default_registry
            registry = default_registry()
        try:
            takes = param_specs(registry.get(kind, value).factory)
        except UnknownComponentError as exc:
            raise ParameterError(f"filter '{who}': {exc}") from None
        return registry.create(kind, value, **{k: v for k, v in handed.items() if k in takes})
    specs = param_specs(type(value))
    own = value.get_params()
    defaults = owner_defaults or {}
    changed = {}
    for k, v in handed.items():
        if k not in specs or own[k] == v:
            continue
        if own[k] == specs[k].default:
            changed[k] = v
        elif k not in defaults or v != defaults[k]:
            raise ParameterError(
                f"filter '{who}': {k} = {v!r} conflicts with the {kind} step "
                f"'{type(value).registry_name or type(value).__name__}' {k} = {own[k]!r}; set it in one place")
    return type(value)(**{**own, **changed}) if changed else value
