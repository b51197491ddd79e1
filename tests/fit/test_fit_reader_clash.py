"""A third party's reader that claims ``.psv`` too leaves a fit possible: the user names the format
for their file, and the fit reads its own copy of the observations with the reader that wrote it
(it had re-read the copy by suffix, found two readers and failed every fit of a .psv file)."""
from __future__ import annotations

from cistrack.fitting.from_observations import fit_files
from cistrack.plugin.registry import load_registry
from cistrack.plugins.readers.ades_psv import AdesPsvReader
from cistrack.scenario.builtin_scenarios import builtin_scenario_path


class OtherPsv(AdesPsvReader):
    """Another format whose files end in .psv; it reads nothing of ours."""

    def read(self, path, epoch):
        raise AssertionError("the other .psv reader was asked to read")


def test_a_fit_with_the_format_named_reads_its_own_copy_with_the_reader_that_wrote_it(tmp_path):
    reg = load_registry(autoload_third_party=False)
    reg.add("reader", "other-psv", OtherPsv)
    obs = builtin_scenario_path("real-data").parent / "real_data" / "observations.psv"
    (one,) = fit_files([obs], out=tmp_path / "fit", registry=reg, settings=["measurements.reader.name=ades-psv"])
    assert one.ok
