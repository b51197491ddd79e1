"""A scenario asks each component how much memory it will need (``Component.memory_need``) and
refuses, before the run, what cannot fit, naming the parameter the component names."""
from __future__ import annotations

import pytest

import cistrack.scenario.limits as limits
from cistrack.errors import ConfigError
from cistrack.interfaces.component import BYTES_PER_PARTICLE, IOD_CHUNK_BYTES, MemoryNeed, check_int
from cistrack.plugin.registry import load_registry
from cistrack.plugins.filters.enkf import EnKFFilter as EnKF
from cistrack.plugins.iod.kinematic_presets import NoisyRangeIOD
from cistrack.scenario.loading import load_scenario


class WideEnKF(EnKF):
    """An EnKF whose memory grows with its own parameter, ``n_members``.

    Parameters
    ----------
    n_members : int
        Ensemble members.
    """

    def __init__(self, n_members: int = 100):
        super().__init__(n_particles=100)
        self.n_members = check_int(self, "n_members", n_members, minimum=2)

    def memory_need(self) -> MemoryNeed:
        return MemoryNeed(self.n_members * 1e6, "n_members", self.n_members, f"{self.n_members:g} members")


def test_particle_filters_and_iod_state_their_particles():
    assert EnKF(n_particles=1000).memory_need() == MemoryNeed.particles(1000)
    assert NoisyRangeIOD(n_particles=1000).memory_need().bytes == 1000 * BYTES_PER_PARTICLE + IOD_CHUNK_BYTES


def test_a_component_that_names_its_own_parameter_is_refused_by_that_parameter(monkeypatch):
    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 2 ** 30)
    reg = load_registry(autoload_third_party=False)
    reg.add("filter", "wide-enkf", WideEnKF)
    with pytest.raises(ConfigError, match=r"\[filter\]: key 'n_members' = 5000: 'wide-enkf' with 5000 members"):
        load_scenario("quick", reg, overrides={"filter": {"name": "wide-enkf", "n_members": 5000}})


def test_a_component_without_a_need_is_not_checked(monkeypatch):
    monkeypatch.setattr(limits, "available_memory_bytes", lambda: 2 ** 30)
    scen = load_scenario("quick", overrides={"filter": {"name": "ukf"}})
    assert scen.components["filter"].memory_need() is None
