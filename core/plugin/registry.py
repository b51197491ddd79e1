"""The component registry, filled by plugins through pluggy and entry points.

Each entry point of the group ``cistrack`` is loaded on its own: a plugin that fails to import
or to register (any exception, ``sys.exit`` and KeyboardInterrupt included) is recorded in
:attr:`Registry.failures` with its distribution, entry point and error, a warning goes to the
``cistrack`` logger, and the others still load. A plugin that registers a name already taken is such a
failure too (the message names both sources); the first registration stays, and built-ins
load first, so a third party can never silently replace a built-in. ``CISTRACK_DISABLE_PLUGIN_AUTOLOAD=1`` loads only the
built-in components (distribution ``cistrack``).
"""
from __future__ import annotations

import logging
import traceback
from dataclasses import dataclass
from importlib import metadata
from typing import Any

import pluggy

from cistrack.plugin import hookspecs
from cistrack.env_flags import env_flag
from cistrack.errors import DuplicateComponentError, ParameterError, RunInterrupted, UnknownComponentError, quoted
from cistrack.interfaces import KINDS

__all__ = ["Registration", "PluginFailure", "Registry", "default_registry", "load_registry",
           "AUTOLOAD_ENV", "ENTRY_POINT_GROUP"]

ENTRY_POINT_GROUP = "cistrack"
AUTOLOAD_ENV = "CISTRACK_DISABLE_PLUGIN_AUTOLOAD"
BUILTIN_DISTRIBUTION = "cistrack"
_HOOK_NAMES = tuple(n for n in vars(hookspecs.CistrackSpecs) if n.startswith("cistrack_"))


@dataclass(frozen=True)
class Registration:
    """A registered component: the factory (class or object) and where it came from."""

    kind: str
    name: str
    factory: Any
    distribution: str
    version: str
    entry_point: str

    @property
    def summary(self) -> str:
        """The factory's description or the first paragraph of its docstring, plain text, one line."""
        from cistrack.plugin.param_docs import summary_of

        return summary_of(self.factory)

    @property
    def source(self) -> str:
        return f"{self.distribution} {self.version} (entry point '{self.entry_point}')"


@dataclass(frozen=True)
class PluginFailure:
    """A plugin that could not be loaded or could not register."""

    distribution: str
    entry_point: str
    error: str
    detail: str

    def __str__(self) -> str:
        return f"{self.distribution}: entry point '{self.entry_point}' failed: {self.error}"


class _BoundRegistry:
    """What a plugin's ``cistrack_register`` receives: adds on behalf of one entry point."""

    def __init__(self, registry: "Registry", distribution: str, version: str, entry_point: str):
        self._registry = registry
        self._source = (distribution, version, entry_point)
        self.added: list[tuple[str, str]] = []  # (kind, name), taken back if the plugin then fails

    def add(self, kind: str, name: str, factory: Any) -> None:
        """Register ``factory`` (a component class, or an object for kinds 'orbit') as ``name``."""
        self._registry.add(kind, name, factory, *self._source)
        self.added.append((kind, name))


class Registry:
    """Named components of each kind (see :data:`cistrack.interfaces.KINDS`)."""

    def __init__(self) -> None:
        self._entries: dict[str, dict[str, Registration]] = {k: {} for k in KINDS}
        self.failures: list[PluginFailure] = []
        self.plugins: list[tuple[str, str, Any]] = []  # (distribution, entry point, module)

    # -- filling ----------------------------------------------------------------------------------
    def add(self, kind: str, name: str, factory: Any, distribution: str = "<local>",
            version: str = "", entry_point: str = "<direct>") -> None:
        """Register ``factory`` under ``kind``/``name``; a duplicate name names both sources."""
        if kind not in self._entries:
            raise ParameterError(f"unknown component kind {kind!r}; kinds are: {', '.join(KINDS)}")
        reg = Registration(kind, name, factory, distribution, version, entry_point)
        _check_registration(reg)
        old = self._entries[kind].get(name)
        if old is not None:
            raise DuplicateComponentError(
                f"{kind} '{name}' is registered twice: by {old.source} and by {reg.source}")
        if isinstance(factory, type) and hasattr(factory, "registry_name") and not factory.__dict__.get("registry_name"):
            factory.registry_name = name
        if kind == "reader":
            self._warn_shared_suffixes(reg)
        self._entries[kind][name] = reg

    def _warn_shared_suffixes(self, reg: Registration) -> None:
        """Warn when reader ``reg`` claims a file-name suffix that a reader of another distribution
        claims: files ending so must then be read with the format named (``reader.name``)."""
        mine = {str(x).lower() for x in getattr(reg.factory, "suffixes", ())}
        for other in self._entries["reader"].values():
            shared = sorted(mine & {str(x).lower() for x in getattr(other.factory, "suffixes", ())})
            if shared and other.distribution != reg.distribution:
                logging.getLogger("cistrack").warning(
                    f"warning: reader '{reg.name}' ({reg.source}) claims {', '.join(shared)}, as reader "
                    f"'{other.name}' ({other.source}) does: files ending so must be read with the format named "
                    f"(--set measurements.reader.name=...)")

    def load_entry_points(self, autoload_third_party: bool | None = None) -> "Registry":
        """Load every entry point of the group ``cistrack``, each on its own."""
        if autoload_third_party is None:
            autoload_third_party = not env_flag(AUTOLOAD_ENV)  # refused by name unless a yes/no spelling
        elif not isinstance(autoload_third_party, bool):
            raise TypeError(f"autoload_third_party={autoload_third_party!r}: give True, False or None (None: "
                            f"as ${AUTOLOAD_ENV} says)")
        pm = pluggy.PluginManager(hookspecs.PROJECT)
        pm.add_hookspecs(hookspecs.CistrackSpecs)
        idents: dict = {}
        eps = sorted(metadata.entry_points(group=ENTRY_POINT_GROUP),
                     key=lambda e: (_dist_identity(e, idents)[0] != BUILTIN_DISTRIBUTION,
                                    _dist_identity(e, idents)[0], e.name))
        for ep in eps:
            dist, version = _dist_identity(ep, idents)
            if dist != BUILTIN_DISTRIBUTION and not autoload_third_party:
                continue
            bound = _BoundRegistry(self, dist, version, ep.name)
            try:
                module = ep.load()
                pm.register(module, name=f"{dist}:{ep.name}")
                _require_marked_hooks(pm, module)
                _require_known_hooks(pm, module)
                impls = [i for i in pm.hook.cistrack_register.get_hookimpls() if i.plugin is module]
                for impl in impls:
                    impl.function(registry=bound)
                self.plugins.append((dist, ep.name, module))
            except RunInterrupted:  # a real SIGTERM/SIGHUP arrived while loading: stop as asked
                raise
            except BaseException as exc:  # a broken plugin must not stop the others, nor the process:
                # SystemExit (sys.exit on import), KeyboardInterrupt and other BaseExceptions included;
                # what it registered before failing is taken back: a skipped plugin adds nothing
                for kind, name in bound.added:
                    self._entries[kind].pop(name, None)
                self.failures.append(PluginFailure(dist, ep.name, _describe_failure(exc),
                                                   traceback.format_exc()))
                logging.getLogger("cistrack").warning(f"warning: plugin {self.failures[-1]}; it is skipped "
                                                      "(cistrack plugins lists plugins that failed to load)")
        return self

    # -- lookup -----------------------------------------------------------------------------------
    def kinds(self) -> tuple[str, ...]:
        return tuple(self._entries)

    def names(self, kind: str) -> list[str]:
        """Registered names of ``kind``, sorted."""
        self._check_kind(kind)
        return sorted(self._entries[kind])

    def entries(self, kind: str) -> list[Registration]:
        return [self._entries[kind][n] for n in self.names(kind)]

    def get(self, kind: str, name: str) -> Registration:
        """The registration of ``kind``/``name``; unknown names list what is available."""
        self._check_kind(kind)
        try:
            return self._entries[kind][name]
        except (KeyError, TypeError):
            raise UnknownComponentError(self.unknown_message(kind, name)) from None

    def unknown_message(self, kind: str, name: Any) -> str:
        avail = self.names(kind)
        msg = f"unknown {kind} {quoted(name)}; available: {', '.join(avail) if avail else '(none registered)'}"
        import difflib  # on use: only an unknown name needs it

        close = difflib.get_close_matches(str(name), avail, n=1, cutoff=0.5)
        if close:
            msg += f". Did you mean {close[0]!r}?"
        failed = [f for f in self.failures]
        if failed:
            msg += " (plugins that failed to load: " + "; ".join(str(f) for f in failed) + ")"
        return msg

    def describe(self, kind: str, name: str) -> str:
        """``filter 'h-mine' (hplug 0.1)``: a component in messages, with the distribution it came
        from unless it is a built-in (or the name is not registered)."""
        got = self._entries.get(kind, {}).get(name)
        if got is None or got.distribution == BUILTIN_DISTRIBUTION:
            return f"{kind} {name!r}"
        return f"{kind} {name!r} ({got.distribution}{' ' + got.version if got.version else ''})"

    def create(self, kind: str, name: str, **params: Any) -> Any:
        """Build ``kind``/``name`` with ``params`` (validated by the component itself); a parameter
        its constructor does not take is a ParameterError naming the ones it takes."""
        factory = self.get(kind, name).factory
        if isinstance(factory, type) and params and not _takes_any_keyword(factory):
            from cistrack.interfaces.component import param_specs

            known = param_specs(factory)
            unknown = sorted(k for k in params if k not in known)
            if unknown:
                raise ParameterError(f"{self.describe(kind, name)}: unknown parameter {unknown[0]!r}; its parameters: "
                                     f"{', '.join(known) or '(none)'}")
        if isinstance(factory, type) or callable(factory):
            return factory(**params)
        if params:
            raise ParameterError(f"{kind} '{name}' takes no parameters, got {sorted(params)}")
        return factory

    def __contains__(self, item: tuple[str, str]) -> bool:
        kind, name = item
        return name in self._entries.get(kind, {})

    def _check_kind(self, kind: str) -> None:
        if kind not in self._entries:
            raise UnknownComponentError(f"unknown component kind {kind!r}; kinds are: {', '.join(KINDS)}")


def _check_registration(reg: Registration) -> None:
    """Refuse (ParameterError naming the plugin, the kind and the name) a name that is not a
    non-empty string free of whitespace and control characters (a scenario names it in a TOML
    value, a person in a command), and a factory that is not a class for any kind but ``orbit``
    (whose components are objects): an instance would be shared by every run in the process."""
    who = f"plugin {reg.distribution}{' ' + reg.version if reg.version else ''} (entry point '{reg.entry_point}')"
    name = reg.name
    if not isinstance(name, str) or not name or any(c.isspace() or not c.isprintable() for c in name):
        raise ParameterError(f"{who}: {reg.kind} name {name!r} is not allowed: a component name is a non-empty "
                             "string without whitespace or control characters (e.g. 'my-filter')")
    if reg.kind != "orbit" and not isinstance(reg.factory, type):
        raise ParameterError(f"{who}: {reg.kind} {name!r} must be registered as a class (the component's class, "
                             f"built by the registry for each run), got {type(reg.factory).__name__} "
                             f"{_short_repr(reg.factory)}")


def _short_repr(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class _UnmarkedHooks(ParameterError):
    """A plugin module whose hook functions are not marked ``@cistrack.hookimpl``, or whose marked
    functions are named after no cistrack hook."""


def _require_marked_hooks(pm: pluggy.PluginManager, module: Any) -> None:
    """Refuse (:class:`_UnmarkedHooks`) a plugin module that defines a function named after a cistrack
    hook without marking it ``@cistrack.hookimpl``: pluggy would skip it, and the plugin would
    register, observe or add nothing through it, without a word (its marked hooks do not excuse it)."""
    marked = {caller.name for caller in pm.get_hookcallers(module) or []}
    unmarked = [h for h in _HOOK_NAMES if callable(getattr(module, h, None)) and h not in marked]
    if unmarked:
        it, them = ("it is", "it") if len(unmarked) == 1 else ("they are", "them")
        raise _UnmarkedHooks(f"its module {getattr(module, '__name__', module)!s} has {', '.join(unmarked)} but {it} "
                             "not marked @cistrack.hookimpl (from cistrack.api import hookimpl), so cistrack never "
                             f"calls {them}")


def _require_known_hooks(pm: pluggy.PluginManager, module: Any) -> None:
    """Refuse (:class:`_UnmarkedHooks`) a plugin module with a function marked ``@cistrack.hookimpl``
    whose name is no cistrack hook (a misspelt ``cistrack_run_finish``): pluggy would never call it
    (its ``check_pending`` raises ``PluginValidationError`` for exactly this); the message names it,
    the closest hook and every hook (probe L9)."""
    unknown = sorted(c.name for c in pm.get_hookcallers(module) or [] if c.name not in _HOOK_NAMES
                     and not all(i.optionalhook for i in c.get_hookimpls() if i.plugin is module))
    if not unknown:
        return
    import difflib  # only for a plugin that fails: listing components keeps its start lean

    words = []
    for name in unknown:
        close = difflib.get_close_matches(name, _HOOK_NAMES, n=1, cutoff=0.6)
        words.append(f"{name!r}" + (f" (did you mean {close[0]!r}?)" if close else ""))
    raise _UnmarkedHooks(f"its module {getattr(module, '__name__', module)!s} marks @cistrack.hookimpl "
                         f"{', '.join(words)}, which {'is' if len(unknown) == 1 else 'are'} no cistrack hook, so "
                         f"cistrack never calls {'it' if len(unknown) == 1 else 'them'}; the hooks are: "
                         f"{', '.join(_HOOK_NAMES)}")


def _describe_failure(exc: BaseException) -> str:
    """One line for a plugin's import or registration error; for ``sys.exit`` it says so."""
    if isinstance(exc, SystemExit):
        return f"SystemExit: it called sys.exit({exc.code!r}) while loading"
    if isinstance(exc, _UnmarkedHooks):
        return str(exc)
    text = " ".join(str(exc).split())  # one line: a pluggy validation error breaks its own lines
    return f"{type(exc).__name__}: {text}" if text else f"{type(exc).__name__} raised while loading"


def _dist_identity(ep: metadata.EntryPoint, cache: dict) -> tuple[str, str]:
    """(normalised distribution name, version) of ``ep``'s distribution.

    Each ``dist.metadata`` access parses the METADATA file with the email parser (~1 ms): the
    answer is kept per distribution in ``cache`` (all of a distribution's entry points share it)."""
    dist = getattr(ep, "dist", None)
    if dist is None:
        return "<unknown>", ""
    key = str(getattr(dist, "_path", id(dist)))
    if key not in cache:
        meta = dist.metadata
        name = (meta["Name"] or "<unknown>").lower().replace("_", "-")
        cache[key] = (name, meta["Version"] or "")
    return cache[key]


def _takes_any_keyword(cls: type) -> bool:
    """Whether ``cls``'s constructor takes ``**kwargs`` (then any parameter name may be its)."""
    import inspect

    try:
        init = getattr(cls, "__init__")
        return any(p.kind is p.VAR_KEYWORD for p in inspect.signature(init).parameters.values())
    except (TypeError, ValueError):  # no signature to read: leave the check to the constructor
        return True


_DEFAULT: Registry | None = None


def load_registry(autoload_third_party: bool | None = None) -> Registry:
    """A fresh registry filled from the installed entry points."""
    return Registry().load_entry_points(autoload_third_party)


def default_registry() -> Registry:
    """The process-wide registry, loaded on first use."""
    global _DEFAULT
    if _DEFAULT is None:
        _DEFAULT = load_registry()
    return _DEFAULT
