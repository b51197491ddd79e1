"""The ADES XML reader checks what the PSV reader checks: the version, where each structural element
sits, and that fields carry no attributes (a <ra unit="rad"> had been read as degrees)."""
from __future__ import annotations

import pytest

from cistrack.interfaces.reader import FieldError
from cistrack.runs.observation_files import read_observations

OPTICAL = ("<optical><trkSub>X</trkSub><stn>705</stn><obsTime>2026-03-01T01:00:00Z</obsTime>"
           "<ra>{ra}</ra><dec>5.5</dec></optical>")


def _xml(body: str, version: str = "2022") -> str:
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<ades version="{version}">\n{body}\n</ades>\n'


GOOD = f"<obsBlock><obsData>{OPTICAL.format(ra='102.5')}</obsData></obsBlock>"


def _read(tmp_path, text: str):
    p = tmp_path / "obs.xml"
    p.write_text(text)
    return read_observations(p, "2026-03-01T00:00:00Z")


def test_a_well_formed_file_is_read(tmp_path):
    assert len(_read(tmp_path, _xml(GOOD))) == 1


@pytest.mark.parametrize("text, words", [
    (_xml(GOOD, version="1999"), "'1999': ADES versions 2017 and 2022 are read"),
    (_xml(f"<obsBlock>{GOOD}</obsBlock>"), "an ADES <obsBlock> belongs in <ades>"),
    (_xml(OPTICAL.format(ra="102.5")), "an ADES <optical> belongs in <obsData>"),
    (_xml(GOOD.replace("<ra>", '<ra unit="rad">')), "has attributes (unit); ADES fields take none"),
], ids=["version", "nested-block", "optical-at-root", "field-attribute"])
def test_what_ades_does_not_allow_is_refused_naming_it(tmp_path, text, words):
    with pytest.raises(FieldError, match="line") as err:
        _read(tmp_path, text)
    assert words in str(err.value)


def test_a_file_declaring_another_encoding_is_told_that_ades_xml_is_read_in_utf8_only(tmp_path):
    p = tmp_path / "obs.xml"
    text = _xml("<!-- M\u00fcller -->" + GOOD).replace('encoding="UTF-8"', 'encoding="ISO-8859-1"')
    p.write_bytes(text.encode("latin-1"))
    with pytest.raises(FieldError, match=r'obs\.xml, line 3, field \(encoding\): not UTF-8 text \(invalid start '
                                         r'byte\): the file declares encoding="ISO-8859-1", and cistrack reads XML '
                                         r"observation files \(ADES XML\) in UTF-8 only"):
        read_observations(p, "2026-03-01T00:00:00Z")
