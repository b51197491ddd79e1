"""Observations from two sites in one set: each row is predicted from its own site (the site
network's ``for_measurement``), rows of two sites at one time are both used, the truth is
recovered from noise-free data, and the residual table names the site of each row."""
from __future__ import annotations

import numpy as np

from cistrack.astro.site_network import SiteNetwork, merge_sites
from cistrack.astro.sites import Site
from cistrack.least_squares import fit_orbit
from cistrack.model.measurement import MeasurementSet
from cistrack.plugin.registry import default_registry
from cistrack.units import LU_KM, hours_to_tu

from .arcs import EPOCH, GUESS_OFFSET, NRHO, cr3bp_arc

SITES = {"TX": Site(30.618963, -96.339214, 103.8), "CAN": Site(28.7, -17.9, 2400.0)}


def test_two_sites_are_each_predicted_from_their_own_place_and_recover_the_truth():
    dyn = cr3bp_arc().dynamics
    reg = default_registry()
    grid = np.arange(1, 120) * float(hours_to_tu(40.0 / 60.0))
    truth = dyn.propagate(NRHO[None], 0.0, grid).states[:, 0]
    parts, members = [], {}
    for key, site in SITES.items():
        sen = reg.create("sensor", "ground-telescope", epoch=EPOCH, latitude_deg=site.latitude_deg,
                         longitude_deg=site.longitude_deg, height_m=site.height_m)
        seen = sen.visible(truth, grid)
        z = sen.measure(truth[seen], grid[seen])
        parts.append((key, site, MeasurementSet(grid[seen], z, sen.sigmas(truth[seen], grid[seen]), sen.names)))
        members[key] = sen
    ms = merge_sites(parts)
    assert len(ms.time_groups()) < len(ms)          # some times are seen from both sites
    res = fit_orbit(dyn, SiteNetwork(members, ms.times, ms.sites), ms, NRHO + GUESS_OFFSET, 0.0)
    np.testing.assert_array_equal(res.residuals.sites, ms.sites)
    assert res.n_rejected == 0 and res.converged
    assert np.abs(res.state - NRHO)[:3].max() * LU_KM < 1e-6
