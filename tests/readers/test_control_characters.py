"""Control characters from a file or a --set value never reach the terminal raw (an ESC sequence in a
designation had cleared the screen and turned it red): a designation must be printable, and a
value a message shows is escaped."""
from __future__ import annotations

import pytest

from cistrack.errors import shown
from cistrack.interfaces.reader import FieldError
from cistrack.runs.observation_files import read_observations

ROWS = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
{name}|CCD|568|2026-04-21T05:41:06.977992Z|80.63079201692864|32.542837322772766|0.706|0.706|Gaia3
{name}|CCD|568|2026-04-21T05:52:06.977992Z|80.68079201692864|32.532837322772766|0.706|0.706|Gaia3
"""


def test_a_designation_with_a_control_character_is_refused_escaped(tmp_path):
    p = tmp_path / "esc.psv"
    p.write_text(ROWS.format(name="\x1b[2JEVIL"))
    with pytest.raises(FieldError) as err:
        read_observations(p, epoch="2026-04-01T00:00:00Z")
    msg = str(err.value)
    assert "line 3" in msg and "'\\x1b[2JEVIL': a designation must be printable characters" in msg
    assert "\x1b" not in msg


def test_a_printable_value_is_shown_as_it_is():
    assert shown("nrho") == "nrho"


def test_a_value_with_a_control_character_is_shown_escaped():
    assert shown("\x1b[31mred") == "'\\x1b[31mred'"
