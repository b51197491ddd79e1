"""CCSDS KVN messages are ASCII: a non-ASCII designation (an ADES trkSub such as "δρο✓") had gone
verbatim into OBJECT_NAME; it is written as its escape, which reads back to the name."""
from __future__ import annotations

import codecs

from cistrack.plugins.exporters.ccsds_text import kvn_text


def test_a_non_ascii_name_is_escaped_and_reads_back():
    text = kvn_text("oem", ["CCSDS_OEM_VERS = 2.0", "OBJECT_NAME = δρο✓", "COMMENT plain"])
    assert text.isascii()
    name = text.splitlines()[1].partition(" = ")[2]
    assert codecs.decode(name, "unicode_escape") == "δρο✓"


def test_an_ascii_message_is_unchanged():
    lines = ["CCSDS_OEM_VERS = 2.0", "OBJECT_NAME = C2RLB52"]
    assert kvn_text("oem", lines) == "\n".join(lines) + "\n"
