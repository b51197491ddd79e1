"""The run's one line on its IOD: what it fitted, what it left out, what it gave."""
from __future__ import annotations

from cistrack import units

__all__ = ["iod_message"]


def iod_message(name: str, cloud, n_measurements: int) -> str:
    """What the IOD used, counted: 'IOD 'x' on 8 measurements of pass 1 (of 39): 2000 particles'."""
    meta = cloud.meta if isinstance(getattr(cloud, "meta", None), dict) else {}
    used = meta.get("fit_indices")
    if used is None:
        return f"IOD '{name}': {len(cloud)} particles from the {n_measurements} measurements it was given"
    left = "".join(f"; left out of its fit: the measurement at t = {units.tu_to_days(x['t_tu']):.4f} d, "
                   f"{x['offset_arcsec']:,.0f} arcsec off the pass's other measurements (a gross outlier)"
                   for x in meta.get("screened_out") or ())
    return (f"IOD '{name}' on {len(used)} measurements of pass 1 (of {n_measurements} in all): "
            f"{len(cloud)} particles at t = {units.tu_to_days(cloud.epoch):.3f} d{left}")
