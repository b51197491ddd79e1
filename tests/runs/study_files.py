"""The small study files the run and study tests write: the quick scenario, a 300-particle PGM."""
from __future__ import annotations

from pathlib import Path

STUDY = """
name = "{name}"
description = "tiny study for tests"
scenarios = ["quick"]
filters = [{{ name = "pgm", n_particles = 300, n_components = 2 }}]
iod = [{{ name = "noisy-range", n_particles = 300 }}]
seeds = {seeds}
[overrides]
duration_days = {days}
"""


def write_study(directory: Path, name: str = "tiny", seeds: str = "[1, 2, 3]", days: float = 1.4) -> Path:
    """``directory/NAME.toml``: the study above with these seeds (a TOML list) and duration."""
    p = directory / f"{name}.toml"
    p.write_text(STUDY.format(name=name, seeds=seeds, days=days))
    return p
