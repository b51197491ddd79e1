"""An event whose 1-sigma cannot be mapped is printed as undetermined, never as nan."""
from __future__ import annotations

import math

from cistrack.least_squares.events import OrbitEvent, event_lines


def _approach(sigma: dict) -> OrbitEvent:
    return OrbitEvent("closest approach", "Moon", 1.0, "2026-05-05T18:27:46.000Z", 3.088, -23.496, 63704.2, 0.211,
                      "selenographic (mean-Earth, DE421)", sigma)


def test_a_sigma_that_could_not_be_mapped_is_shown_as_undetermined_not_nan():
    text = "\n".join(_approach(dict.fromkeys(("time_s", "latitude_deg", "longitude_deg", "altitude_km",
                                              "speed_kms"), math.nan)).lines())
    assert "nan" not in text and "+- ?" in text and "poorly determined" in text


def test_mapped_sigmas_print_as_numbers():
    text = "\n".join(_approach({"time_s": 74.6, "latitude_deg": 0.0019, "longitude_deg": 0.018,
                                "altitude_km": 5.8, "speed_kms": 1.7e-5}).lines())
    assert "+- 74.6 s" in text and "?" not in text


def test_a_list_of_events_explains_the_question_mark_once_after_them():
    undetermined = dict.fromkeys(("time_s", "altitude_km", "speed_kms"), math.nan)
    lines = event_lines([_approach(undetermined), _approach(undetermined)])
    assert sum("(? : no 1-sigma" in line for line in lines) == 1 and "(? : no 1-sigma" in lines[-1]
