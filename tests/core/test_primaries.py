"""The Earth-Moon constants live in one place and every dynamics model reports its primaries."""
from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from cistrack.astro.primaries import (EARTH_RADIUS_KM, MOON_RADIUS_KM, MU_EARTH_MOON, earth_moon_primaries, mass_ratio)
from cistrack.units import LU_KM

ROOT = Path(__file__).resolve().parents[2]


def test_the_primaries_have_their_barycentre_at_the_origin_and_unit_separation():
    earth, moon = earth_moon_primaries()
    assert earth.mass_fraction + moon.mass_fraction == pytest.approx(1.0, abs=1e-15)
    centre = earth.mass_fraction * earth.position + moon.mass_fraction * moon.position
    np.testing.assert_allclose(centre, 0.0, atol=1e-16)
    assert np.linalg.norm(moon.position - earth.position) == pytest.approx(1.0, abs=1e-15)
    assert moon.mass_fraction == MU_EARTH_MOON


def test_radii_are_converted_to_length_units():
    earth, moon = earth_moon_primaries()
    assert earth.radius * LU_KM == pytest.approx(EARTH_RADIUS_KM)
    assert moon.radius * LU_KM == pytest.approx(MOON_RADIUS_KM)


def test_cr3bp_reports_its_own_mass_ratio_through_its_primaries(registry):
    dyn = registry.create("dynamics", "cr3bp", mu=0.05)
    assert mass_ratio(dyn) == 0.05
    np.testing.assert_allclose(dyn.primary("earth").position, [-0.05, 0.0, 0.0])


def test_a_primary_without_radius_is_no_impact_body(registry):
    dyn = registry.create("dynamics", "cr3bp", earth_radius_km=0.0)
    assert [b.name for b in dyn.primaries] == ["Earth", "Moon"]
    assert [b.name for b in dyn.bodies] == ["Moon"]


def test_a_model_without_a_moon_falls_back_to_the_earth_moon_ratio(registry):
    dyn = registry.create("dynamics", "twobody")
    assert dyn.primary("Moon") is None
    assert mass_ratio(dyn) == MU_EARTH_MOON


def _float_assignments(path: Path) -> list[tuple[int, float]]:
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Constant):
            if isinstance(node.value.value, float):
                out.append((node.lineno, node.value.value))
    return out


def _default_floats(path: Path) -> list[tuple[int, float]]:
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.arguments):
            for d in node.defaults + [d for d in node.kw_defaults if d is not None]:
                if isinstance(d, ast.Constant) and isinstance(d.value, float):
                    out.append((d.lineno, d.value))
    return out


@pytest.mark.parametrize("value,name", [(MU_EARTH_MOON, "mass ratio"), (EARTH_RADIUS_KM, "Earth radius"),
                                        (MOON_RADIUS_KM, "Moon radius")])
def test_no_file_but_primaries_defines_the_earth_moon_constants(value, name):
    offenders = []
    for folder in ("core", "plugins", "examples"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path == ROOT / "core" / "astro" / "primaries.py":
                continue
            for line, v in _float_assignments(path) + _default_floats(path):
                if v == value:
                    offenders.append(f"{path.relative_to(ROOT)}:{line}")
    assert not offenders, f"the {name} is defined outside core/astro/primaries.py: {offenders}"
