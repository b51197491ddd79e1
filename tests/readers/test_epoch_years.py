"""read_observations refuses an epoch outside the years cistrack supports (1800-2200), naming it,
as a scenario's epoch is: the year 1500 had been accepted."""
from __future__ import annotations

import pytest

from cistrack.errors import ConfigError
from cistrack.runs.observation_files import read_observations

PSV = """# version=2022
trkSub|mode|stn|obsTime|ra|dec|rmsRA|rmsDec|astCat
x|CCD|568|2026-05-01T17:15:59.985810Z|215.43149293489537|-19.59906428343243|0.7|0.7|Gaia3
x|CCD|568|2026-05-01T17:23:33.631543Z|215.47228846931684|-19.635680347753723|0.7|0.7|Gaia3
"""


@pytest.mark.parametrize("epoch", ["1500-01-01T00:00:00Z", "2300-01-01T00:00:00Z"])
def test_an_epoch_outside_the_supported_years_is_refused_by_name(tmp_path, epoch):
    (tmp_path / "o.psv").write_text(PSV)
    with pytest.raises(ConfigError, match="epoch = .* is outside the years cistrack supports"):
        read_observations(tmp_path / "o.psv", epoch=epoch)


def test_an_epoch_within_them_reads(tmp_path):
    (tmp_path / "o.psv").write_text(PSV)
    assert len(read_observations(tmp_path / "o.psv", epoch="2026-05-01T00:00:00Z")) == 2
