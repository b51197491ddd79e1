from __future__ import annotations

from pathlib import Path

import pytest

STUDY = """
name = "tiny"
description = "tiny study for tests"
scenarios = ["quick"]
filters = [{{ name = "pgm", n_particles = 300, n_components = 2 }}]
iod = [{{ name = "noisy-range", n_particles = 300 }}]
seeds = {seeds}
[overrides]
duration_days = {days}
"""


@pytest.fixture
def tiny_study(tmp_path) -> Path:
    p = tmp_path / "tiny.toml"
    p.write_text(STUDY.format(seeds="[1, 2, 3]", days=1.4))
    return p
