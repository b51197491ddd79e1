"""Radiation pressure beside a maneuver, for a fit that looked like one no burn measured.

``area_to_mass = "auto"`` tries the ratio C_R A/m only over arcs of 10 days or more
(:data:`cistrack.least_squares.area_to_mass.MIN_ARC_DAYS`): over a shorter arc a 6-parameter orbit
absorbs most of the pressure of a rocket stage. An object with a large ratio (0.2 m^2/kg: some
300 km in 10 days) is not absorbed: its ballistic fit rejects a night or leaves it off together,
which reads as a maneuver, and when the burn search measures no burn either the fit had failed
"it looks like an object that maneuvered" with no word of the ratio that fits it (probe N7).

So when the burn search has measured nothing, the fit is made once more with the ratio solved
for (from the ballistic state, every observation in its first pass). :func:`pressure_explains`
gives it when it is clean (converged, not suspect of a maneuver by
:func:`~cistrack.least_squares.burn_search.suspicion`) and the ratio passes the test "auto"
applies (:func:`~cistrack.least_squares.area_to_mass.area_to_mass_verdict`: significant at 3
sigma, physical, the chi-square lower by 9 or more). The fit's words then offer it; the fit is
not replaced by it, since a burn the arc cannot measure fits as cleanly (a survey set's 0.3 m/s
burn: 0.19 m^2/kg at 13 sigma, that orbit 660,000 in Mahalanobis^2 from the truth).
"""
from __future__ import annotations

from dataclasses import replace
from typing import Any

from cistrack import units

__all__ = ["pressure_explains"]


def pressure_explains(ctx: Any, one: Any, r: Any, say: Any = None) -> Any | None:
    """The fit of ``one``'s observations (``ctx``: its run's context) with the radiation pressure's
    ratio solved for, when it fits cleanly what made the ballistic fit ``r`` look like a maneuver
    (module docstring), its ``area_to_mass_decision`` saying so; None when it does not, or when the
    ratio was not left to the fit ("auto") or is already among ``r``'s parameters; ``say`` (a
    function of one line, or None) is told when the fit is made."""
    from cistrack.errors import MeasurementError, PropagationError
    from cistrack.least_squares.differential_correction import fit_orbit
    from cistrack.least_squares.area_to_mass import MIN_ARC_DAYS, area_to_mass_verdict
    from cistrack.least_squares.burn_search import suspicion
    from cistrack.least_squares.errors import FitError
    from cistrack.least_squares.options import AREA_TO_MASS

    opts = one.choices.options
    if opts.area_to_mass != "auto" or AREA_TO_MASS in tuple(r.parameter_names) \
            or AREA_TO_MASS not in tuple(getattr(ctx.dynamics, "solve_for_parameters", ())):
        return None
    if say is not None:
        say(f"{one.designation}: no burn measured; fitting radiation pressure (C_R A/m solved for) instead")
    try:
        seven = fit_orbit(ctx.dynamics, ctx.sensor, ctx.measurements, r.state, r.epoch,
                          options=replace(opts, area_to_mass="solve"))
    except (FitError, PropagationError, MeasurementError):
        return None
    if not seven.converged or suspicion(seven) or area_to_mass_verdict(r, seven) is not None:
        return None
    value, sigma = seven.parameter(AREA_TO_MASS)
    days = float(units.tu_to_days(ctx.measurements.times.max() - ctx.measurements.times.min()))
    short = f" (the arc, {days:.3g} days, is shorter than the {MIN_ARC_DAYS:g} 'auto' tries it over alone)" \
        if days < MIN_ARC_DAYS else ""
    return replace(seven, area_to_mass_decision=(
        f"estimated ({value:.4g} +- {sigma:.2g} m^2/kg) because the ballistic fit looked like a maneuver that no "
        f"burn measured, and radiation pressure fits it cleanly{short}"))
