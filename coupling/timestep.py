"""The time-step rules every run follows: a given step is refused above the stable one, and
the step count ends the run exactly at t_end."""
from __future__ import annotations

import math

from .params import CaseError


def time_step(p: dict, dt_stable: float) -> float:
    """clock.dt if given (refused above the stable step), else clock.safety x stable step (s)."""
    if p["clock.dt"] > dt_stable:
        raise CaseError(f"clock.dt = {p['clock.dt']:g}: above the stable step; allowed <= {dt_stable:.4g} s")
    return p["clock.dt"] or p["clock.safety"] * dt_stable


def n_steps(p: dict, t_end_default: float, dt: float) -> tuple[int, float]:
    """(steps, dt) such that steps * dt = t_end exactly, dt not above the given dt."""
    t_end = p["clock.t_end"] or t_end_default
    ratio = t_end / dt
    if not ratio <= p["clock.max_steps"]:  # (also inf: a denormal dt) refused before anything runs
        raise CaseError(f"clock.max_steps = {p['clock.max_steps']}: this run needs {ratio:.3g} clock steps "
                        f"({t_end:.4g} s at dt = {dt:.4g} s); allowed: raise clock.max_steps, or shorten clock.t_end "
                        "or raise clock.dt")
    n = max(1, math.ceil(ratio - 1e-9))
    return n, t_end / n
