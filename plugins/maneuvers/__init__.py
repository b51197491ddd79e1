"""Built-in maneuver plugins: burn plans for simulated truths (``maneuver-plan``) and maneuver
detectors (``maneuver-detector``)."""
