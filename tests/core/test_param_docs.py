"""Every parameter of every built-in is discoverable: type, default, unit and a whole meaning."""
from __future__ import annotations

import re
import warnings
from pathlib import Path

import pytest

from cistrack.cli.main import main
from cistrack.errors import ParameterError
from cistrack.interfaces import KINDS
from cistrack.plugin.param_docs import (components_markdown, param_docs, parse_parameters_section, plain_text, unit_of)
from cistrack.plugin.registry import load_registry

ROOT = Path(__file__).resolve().parents[2]
REG = load_registry(autoload_third_party=False)
BUILTINS = [e for k in KINDS for e in REG.entries(k) if isinstance(e.factory, type)]


def test_numpydoc_groups_document_each_name():
    doc = """Summary.

    Parameters
    ----------
    a, b : float
        Shared meaning,
        on two lines.
    c : int
        Own meaning.

    Notes
    -----
    d : not a parameter
    """
    assert parse_parameters_section(doc) == {"a": "Shared meaning, on two lines.", "b": "Shared meaning, on two lines.",
                                             "c": "Own meaning."}


def test_markup_is_removed():
    assert plain_text("one of ``FRAME_MODELS`` (:class:`~cistrack.model.belief.ParticleCloud`, *x*)") == \
        "one of FRAME_MODELS (ParticleCloud, x)"


@pytest.mark.parametrize("name, unit", [("range_max_km", "km"), ("max_speed_kms", "km/s"), ("height_m", "m"),
                                        ("velocity_noise_kms_per_sqrt_day", "km/s per sqrt(day)"),
                                        ("n_particles", "")])
def test_units_follow_the_name_suffix(name, unit):
    assert unit_of(name) == unit


@pytest.mark.parametrize("entry", BUILTINS, ids=lambda e: f"{e.kind}-{e.name}")
def test_every_builtin_parameter_has_a_whole_plain_meaning(entry):
    for p in param_docs(entry.factory):
        assert p.meaning, f"{entry.kind} '{entry.name}': parameter '{p.name}' is undocumented"
        assert p.meaning.endswith((".", ")")), f"{entry.name}.{p.name}: {p.meaning!r} is cut mid-sentence"
        assert not re.search(r"``|:[a-z]+:`|`", p.meaning), f"{entry.name}.{p.name}: markup left in"


def test_gauss_describes_each_window_parameter_in_full():
    """Each had read only "first, middle and last measurement of that window.": the words on the
    grouped names' line stood where numpydoc puts the type, which the parser rightly skips."""
    meaning = {p.name: p.meaning for p in param_docs(REG.get("iod", "gauss").factory)}
    assert meaning["pass_gap_hours"].startswith("A gap between measurements longer than this ends the first pass")
    assert meaning["fit_fraction"].startswith("Fraction of the first pass's measurements")
    assert meaning["min_fit"] == meaning["max_fit"] == "Bounds on the number of measurements in the window."


@pytest.mark.parametrize("entry", BUILTINS, ids=lambda e: f"{e.kind}-{e.name}")
def test_the_listing_summary_is_a_whole_plain_sentence(entry):
    assert entry.summary.endswith((".", ")")), f"{entry.name}: {entry.summary!r} is cut"
    assert "`" not in entry.summary and "\n" not in entry.summary


def test_plugins_name_prints_every_parameter_with_type_default_and_meaning(capsys):
    assert main(["plugins", "ground-telescope"]) == 0
    out = capsys.readouterr().out
    cls = REG.get("sensor", "ground-telescope").factory
    for p in param_docs(cls):
        assert f"{p.name} : {p.type} = {p.default!r}" in out
        assert " ".join(p.meaning.split()) in " ".join(out.split())  # wrapped to 120 columns
    assert "sigma_arcsec : float = 1.5 [arcsec]" in out


def test_plugins_with_an_unknown_name_suggests_the_closest(capsys):
    assert main(["plugins", "pgn"]) == 2
    assert "did you mean 'pgm'" in capsys.readouterr().err


def test_components_document_is_up_to_date():
    """Regenerate with: python -m cistrack.plugin.components_doc > docs/components.md"""
    assert (ROOT / "docs" / "components.md").read_text() == components_markdown(REG)


def test_filters_that_carry_particles_all_call_their_number_n_particles():
    for name in ("pgm", "sir", "enkf"):
        assert "n_particles" in {p.name for p in param_docs(REG.get("filter", name).factory)}


def test_enkf_n_members_is_a_deprecated_alias_of_n_particles():
    enkf = REG.get("filter", "enkf").factory
    with pytest.warns(FutureWarning, match="n_members.*deprecated.*n_particles"):
        f = enkf(n_members=300)
    assert f.n_particles == 300
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert enkf(n_particles=300).n_particles == 300
    with pytest.raises(ParameterError, match="n_members"):
        enkf(n_particles=200, n_members=300)
