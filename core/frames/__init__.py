"""Reference frames: :mod:`.earth_moon` holds the real Earth-Moon rotating frame (from DE421) and
its transforms to and from GCRS."""
