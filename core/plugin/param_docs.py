"""Every parameter of a component: type, default, unit and meaning, from one source.

The source is the component's class: ``__init__``'s signature gives names, types and defaults
(:func:`cistrack.interfaces.component.param_specs`); the class docstring's numpydoc ``Parameters``
section gives the meaning (``a, b : float`` documents two parameters at once); the unit
comes from the parameter's name suffix (``_km``, ``_kms``, ``_deg``, ...; see :data:`UNITS`),
the project's naming rule for quantities a person writes. ``cistrack plugins NAME`` prints
this, and ``docs/components.md`` is generated from it (``python -m cistrack.plugin.components_doc``;
a test keeps the file up to date).
"""
from __future__ import annotations

import inspect
import re
from dataclasses import dataclass
from typing import Any

from cistrack.interfaces.component import param_specs

__all__ = ["ParamDoc", "UNITS", "param_docs", "parse_parameters_section", "plain_text", "unit_of",
           "describe_component", "components_markdown", "summary_of"]

UNITS: tuple[tuple[str, str], ...] = (
    ("_kms_per_sqrt_day", "km/s per sqrt(day)"),
    ("_km3s2", "km^3/s^2"),
    ("_kms", "km/s"),
    ("_cms", "cm/s"),
    ("_ms", "m/s"),
    ("_km", "km"),
    ("_m", "m"),
    ("_deg", "deg"),
    ("_arcsec", "arcsec"),
    ("_days", "days"),
    ("_hours", "hours"),
    ("_minutes", "minutes"),
    ("_s", "s"),
)
"""Name suffix -> unit, longest first. A name without one is nondimensional or a choice."""


@dataclass(frozen=True)
class ParamDoc:
    """One documented constructor parameter."""

    name: str
    type: str
    default: Any
    required: bool
    unit: str
    meaning: str


def unit_of(name: str) -> str:
    """The unit a parameter's name states (``range_km`` -> 'km'), '' when it states none."""
    for suffix, unit in UNITS:
        if name.endswith(suffix):
            return unit
    return ""


_ROLE = re.compile(r":[a-z]+:`~?([^`]+)`")


def plain_text(text: str) -> str:
    """Docstring prose without reStructuredText markup, on one line."""
    text = _ROLE.sub(lambda m: m.group(1).rsplit(".", 1)[-1] if m.group(0).startswith(":") and "~" in m.group(0)
                     else m.group(1), text)
    text = re.sub(r"``([^`]*)``", r"\1", text)
    text = re.sub(r"`([^`]*)`", r"\1", text)
    text = re.sub(r"\*\*([^*]+)\*\*", r"\1", text)
    text = re.sub(r"(?<![\w*])\*([^*\s][^*]*)\*(?![\w*])", r"\1", text)
    return " ".join(text.split())


def parse_parameters_section(doc: str | None) -> dict[str, str]:
    """Parameter name -> meaning (plain text) from a numpydoc ``Parameters`` section."""
    if not doc:
        return {}
    lines = inspect.cleandoc(doc).splitlines()
    out: dict[str, str] = {}
    i = 0
    while i < len(lines) - 1:
        if lines[i].strip() == "Parameters" and set(lines[i + 1].strip()) == {"-"}:
            break
        i += 1
    else:
        return {}
    i += 2
    names: list[str] = []
    body: list[str] = []

    def flush() -> None:
        if names:
            meaning = plain_text(" ".join(body))
            for n in names:
                out[n] = meaning

    while i < len(lines):
        line = lines[i]
        if line.strip() and not line.startswith((" ", "\t")):
            if i + 1 < len(lines) and set(lines[i + 1].strip()) == {"-"} and lines[i + 1].strip():
                break  # the next section
            flush()
            head = line.split(":", 1)[0] if " : " in line or line.rstrip().endswith(":") else line
            names = [n.strip() for n in head.split(",") if n.strip()]
            body = []
        elif not line.strip() and names and i + 1 < len(lines) and lines[i + 1].strip() \
                and not lines[i + 1].startswith((" ", "\t")):
            flush()
            names, body = [], []
        else:
            body.append(line.strip())
        i += 1
    flush()
    return out


def _type_name(ann: Any) -> str:
    if ann is Any or ann is inspect.Parameter.empty:
        return "any"
    if isinstance(ann, type):
        return ann.__name__
    text = str(ann).replace("typing.", "")
    return re.sub(r"\b(?:[a-z_]+\.)+([A-Za-z_]+)", r"\1", text)


def _all_docs(cls: type) -> dict[str, str]:
    """Parameter meanings from the class and its bases (a subclass may document only its own)."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        out.update(parse_parameters_section(klass.__dict__.get("__doc__")))
        init = klass.__dict__.get("__init__")
        out.update(parse_parameters_section(getattr(init, "__doc__", None)))
    return out


def param_docs(cls: type) -> list[ParamDoc]:
    """Every constructor parameter of ``cls`` with type, default, unit and meaning ('' if undocumented)."""
    meanings = _all_docs(cls)
    return [ParamDoc(s.name, _type_name(s.annotation), s.default, s.required, unit_of(s.name),
                     meanings.get(s.name, ""))
            for s in param_specs(cls).values()]


def summary_of(factory: Any) -> str:
    """A component's summary: the first paragraph of its description or docstring, plain text,
    on one line (never cut mid-sentence)."""
    doc = getattr(factory, "description", None) or getattr(factory, "__doc__", None) or ""
    paragraph = inspect.cleandoc(doc).split("\n\n", 1)[0] if doc.strip() else ""
    return plain_text(paragraph)


def _default_text(p: ParamDoc) -> str:
    return "(required)" if p.required else repr(p.default)


def describe_component(kind: str, name: str, factory: Any, source: str = "") -> str:
    """Text for ``cistrack plugins NAME``: summary, then one block per parameter."""
    lines = [f"{kind} '{name}'" + (f"  [{source}]" if source else ""), f"  {summary_of(factory)}"]
    if not isinstance(factory, type):
        lines.append("  (a ready-made object: no parameters)")
        return "\n".join(lines)
    docs = param_docs(factory)
    if not docs:
        lines.append("  no parameters")
    else:
        lines.append("  parameters:")
    for p in docs:
        unit = f" [{p.unit}]" if p.unit else ""
        lines.append(f"    {p.name} : {p.type} = {_default_text(p)}{unit}")
        lines.append(f"        {p.meaning or '(undocumented)'}")
    return "\n".join(lines)


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|")


def components_markdown(registry) -> str:
    """docs/components.md: every built-in component and its parameters."""
    from cistrack.interfaces import KINDS

    out = ["# Components and their parameters", "",
           "Generated from the components' docstrings by `python -m cistrack.plugin.components_doc > docs/components.md`",
           "(the same text as `cistrack plugins NAME`); `tests/core/test_param_docs.py` fails when this file",
           "is out of date. Units follow from parameter names (`_km`, `_kms`, `_deg`, ...); internal",
           "states are nondimensional synodic.", ""]
    for kind in KINDS:
        entries = [e for e in registry.entries(kind) if e.distribution == "cistrack"]
        if not entries:
            continue
        out += [f"## {kind}", ""]
        for e in entries:
            out += [f"### `{e.name}`", "", summary_of(e.factory), ""]
            if not isinstance(e.factory, type):
                out += ["A ready-made object (no parameters).", ""]
                continue
            docs = param_docs(e.factory)
            if not docs:
                out += ["No parameters.", ""]
                continue
            out += ["| parameter | type | default | unit | meaning |", "|---|---|---|---|---|"]
            for p in docs:
                out.append(f"| `{p.name}` | {_md_cell(p.type)} | `{_md_cell(_default_text(p))}` | "
                           f"{p.unit or '-'} | {_md_cell(p.meaning or '(undocumented)')} |")
            out.append("")
    return "\n".join(out).rstrip() + "\n"
