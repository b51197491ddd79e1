"""A throwaway plugin distribution in a folder put on ``sys.path`` or ``PYTHONPATH``: a dist-info
with its METADATA and entry points (group ``cistrack``) beside the plugin modules, as an installed
package would leave them, without pip."""
from __future__ import annotations

from pathlib import Path


def plugin_site(site: Path, dist: str, version: str, modules: dict[str, str],
                entry_points: dict[str, str] | None = None) -> Path:
    """Write distribution ``dist`` ``version`` into ``site``: each of ``modules`` (name -> source)
    as ``NAME.py``, and its entry points (entry name -> module; default: each module under its own
    name). Returns ``site``."""
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir(parents=True)
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    points = entry_points if entry_points is not None else {m: m for m in modules}
    (info / "entry_points.txt").write_text("[cistrack]\n" + "".join(f"{e} = {m}\n" for e, m in points.items()))
    for module, body in modules.items():
        (site / f"{module}.py").write_text(body)
    return site


def registry_with_module(folder: Path, module: str, source: str, dist: str, entry_point: str):
    """The default registry with ``source`` loaded as module ``module`` (written to ``folder``) among
    its plugins, as the entry point ``entry_point`` of distribution ``dist`` would add it."""
    import importlib.util

    from cistrack.plugin.registry import load_registry

    path = folder / f"{module}.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location(module, path)
    loaded = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(loaded)
    reg = load_registry()
    reg.plugins.append((dist, entry_point, loaded))
    return reg
