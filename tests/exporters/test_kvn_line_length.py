"""CCSDS KVN files (OEM, OPM) have lines of at most 254 characters (CCSDS 502.0-B-3): a long
comment goes on over several COMMENT lines, wrapped at spaces, and a name too long for its keyword
line is refused naming the keyword and the limit rather than cut short (a shortened OBJECT_ID would
no longer identify the object)."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError
from cistrack.plugin.registry import default_registry
from cistrack.plugins.exporters.opm import read_opm
from cistrack.testing.checks_exporter import sample_inertial_estimates

SITES = ", ".join(f"S{k:02d}" for k in range(80))
LONG = f"least-squares orbit of cis0001 from 534 observations (sites {SITES}): weighted RMS 1.2"


def _write(tmp_path, format, **meta):
    path = tmp_path / f"x.{format}"
    default_registry().create("exporter", format).write(path, sample_inertial_estimates(),
                                                          {"object_name": "t", "object_id": "t", **meta})
    return path.read_text().splitlines()


@pytest.mark.parametrize("format", ["oem", "opm"])
def test_every_line_of_a_file_with_a_long_comment_is_at_most_254_characters(tmp_path, format):
    lines = _write(tmp_path, format, comments=[LONG, "WARNING: " + LONG], data_comment=LONG)
    assert max(len(line) for line in lines) <= 254


@pytest.mark.parametrize("format", ["oem", "opm"])
def test_a_long_comment_is_wrapped_at_spaces_over_comment_lines_that_keep_every_word(tmp_path, format):
    lines = _write(tmp_path, format, comments=[LONG])
    wrapped = [line for line in lines[1:] if line.startswith("COMMENT")][:2]
    assert len(LONG) > 254 and " ".join(line[len("COMMENT "):] for line in wrapped) == LONG


def test_an_oem_whose_comments_were_wrapped_is_read_by_the_independent_oem_package(tmp_path):
    oem = pytest.importorskip("oem")
    lines = _write(tmp_path, "oem", comments=[LONG], data_comment=LONG)
    seg = oem.OrbitEphemerisMessage.open(str(tmp_path / "x.oem")).segments[0]
    assert max(map(len, lines)) <= 254 and len(list(seg.states)) == 4 and seg.metadata["OBJECT_NAME"] == "t"


def test_an_opm_whose_comments_were_wrapped_reads_back(tmp_path):
    lines = _write(tmp_path, "opm", comments=[LONG], data_comment=LONG)
    assert max(map(len, lines)) <= 254 and read_opm(tmp_path / "x.opm")["REF_FRAME"] == "ICRF"


@pytest.mark.parametrize("format", ["oem", "opm"])
@pytest.mark.parametrize("key, meta", [("OBJECT_NAME", "object_name"), ("OBJECT_ID", "object_id")])
def test_a_name_too_long_for_its_line_is_refused_naming_the_keyword_and_the_limit(tmp_path, format, key, meta):
    with pytest.raises(ConfigError, match=rf"exporter '{format}': {key} 'xxx.*' has 300 characters; .* at most 254 "
                                          "characters"):
        _write(tmp_path, format, **{meta: "x" * 300})
