"""The PGM's clusterer: a registry name or an instance, with the filter's n_components."""
from __future__ import annotations

import numpy as np

from cistrack.errors import FilterError, ParameterError
from cistrack.interfaces import Clusterer

__all__ = ["resolve_clusterer", "split_clusterer", "within_asked"]


def resolve_clusterer(clusterer: Clusterer | str, n_components: int | None, registry=None) -> Clusterer:
    """The PGM's clusterer, with the PGM's ``n_components`` where the clusterer takes one.

    In a scenario the clusterer arrives built (through the run's registry, also when left at
    its default name). A name given in Python is created through ``registry`` (default: the
    installed plugins). The rule for ``n_components``: a clusterer left at its class default
    gets the PGM's value (on a copy; the caller's instance is not modified); one whose own
    ``n_components`` was set to a different value is refused with a ParameterError (set it in
    one place).
    """
    if isinstance(clusterer, str):
        if registry is None:
            from cistrack.api import default_registry
            registry = default_registry()
        cls = registry.get("clustering", clusterer).factory
        takes_m = n_components is not None and "n_components" in _params_of(cls)
        return registry.create("clustering", clusterer, **({"n_components": n_components} if takes_m else {}))
    specs = _params_of(type(clusterer))
    if n_components is None or "n_components" not in specs:
        return clusterer
    own = clusterer.get_params()["n_components"]
    if own == n_components:
        return clusterer
    if own != specs["n_components"].default:
        raise ParameterError(
            f"filter 'pgm': n_components = {n_components} conflicts with the clusterer "
            f"'{type(clusterer).registry_name or type(clusterer).__name__}' n_components = {own}; "
            "set it in one place (a clusterer left at its default takes the filter's n_components)")
    params = clusterer.get_params()
    params["n_components"] = n_components
    return type(clusterer)(**params)


def split_clusterer(clusterer: Clusterer | str, resolved: Clusterer, n_split: int | None,
                    registry=None) -> Clusterer | None:
    """The clusterer the PGM uses at a sharp measurement: ``resolved`` (the filter's clusterer)
    asked for ``n_split`` components, on a copy. None when splitting is off or the clusterer
    chooses its own number of components (it takes no ``n_components``)."""
    if not n_split or "n_components" not in _params_of(type(resolved)):
        return None
    params = resolved.get_params()
    params["n_components"] = int(n_split)
    return type(resolved)(**params)


def _params_of(cls) -> dict:
    from cistrack.interfaces.component import param_specs
    return param_specs(cls)


def within_asked(labels: np.ndarray, clusterer: Clusterer, who: str) -> np.ndarray:
    """``labels`` (N,) int of ``clusterer``, refused (FilterError naming ``who``) when they make more
    clusters than its ``n_components`` asks for and it does not choose its own number
    (``chooses_n_components``): the contract (docs/plugins.md) allows at most that many. A clusterer
    that returned 50 for 4 had left every cluster under ``min_cluster_size``, and the PGM ran the
    whole run with one component, without a word (probe N5)."""
    if getattr(clusterer, "chooses_n_components", False) or "n_components" not in _params_of(type(clusterer)):
        return labels
    asked = clusterer.get_params()["n_components"]
    got = int(labels.max()) + 1 if labels.size else 0
    if isinstance(asked, int) and got > asked:
        raise FilterError(f"{who}: cluster() returned {got} clusters where n_components = {asked} asked for at most "
                          f"{asked}; a clusterer returns at most n_components clusters (docs/plugins.md), or "
                          "declares chooses_n_components = True when it picks its own number")
    return labels
