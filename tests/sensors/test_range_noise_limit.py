"""A range sigma (range_alpha x range) of more than the range itself is refused by name, and an IOD
given negative measured ranges says how many and what to change."""
from __future__ import annotations

import pytest

from cistrack.cli.main import main
from cistrack.errors import ParameterError
from cistrack.plugin.registry import default_registry


@pytest.mark.parametrize("sensor", ["ground-telescope", "space-telescope"])
def test_a_range_sigma_above_the_range_is_refused(sensor):
    with pytest.raises(ParameterError, match="'range_alpha'.*\\(0.0, 1.0\\]"):
        default_registry().create("sensor", sensor, range_alpha=10.0)


def test_negative_measured_ranges_are_counted_and_the_sensor_key_named(tmp_path, capsys):
    assert main(["run", "quick", "--set", "sensor.range_alpha=0.9", "--out", str(tmp_path / "r"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "ranges of the first pass are not" in err and "range_alpha" in err
