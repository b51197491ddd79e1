"""What a reader warns of in the user's observation files is said once, naming those files: the
fit's own copies of the observations (observations.psv, observations-early.psv), which each of its
attempts reads again, add no warning of their own."""
from __future__ import annotations

import logging

from cistrack.fitting.from_observations import fit_files
from cistrack.scenario.loading import builtin_scenario_path

DATA = builtin_scenario_path("real-data").parent / "real_data"


def test_a_reader_warning_is_given_once_per_field_for_the_users_file_only(tmp_path, caplog):
    lines = (DATA / "observations.psv").read_text().splitlines()
    rows = [r.split("|") for r in lines[2:22]]            # 20 observations, uncertainties of 1e-6 arcsec
    path = tmp_path / "tiny.psv"
    path.write_text("\n".join(lines[:2] + ["|".join(r[:6] + ["1e-6", "1e-6"] + r[8:]) for r in rows]) + "\n")
    with caplog.at_level(logging.WARNING, logger="cistrack.readers"):
        fit_files([path], out=tmp_path / "fit", settings=["iod.n_particles=300", "filter.n_particles=300"])
    said = [r.getMessage() for r in caplog.records if "milliarcsecond" in r.getMessage()]
    assert len(said) == 2 and all(m.startswith(f"{path}, line 3: field rms") for m in said)
