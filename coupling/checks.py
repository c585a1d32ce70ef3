"""Checks against closed forms, recorded in the summary.json "checks" format."""
from __future__ import annotations

import math
import numbers


def check(value: float, reference: float, tol: float, source: str) -> dict:
    """Relative-error check |value - reference| / |reference| <= tol (a non-finite value fails)."""
    if not math.isfinite(value):
        return {"value": None, "reference": float(reference), "rel_err": None, "tol": float(tol),
                "passed": False, "source": source + " (value not finite: the run did not produce it)"}
    rel = abs(value - reference) / abs(reference) if reference else abs(value)
    return {"value": float(value), "reference": float(reference), "rel_err": float(rel),
            "tol": float(tol), "passed": bool(rel <= tol), "source": source}


def bound(value: float, limit: float, source: str, upper: bool = True) -> dict:
    """One-sided check value <= limit (upper) or value >= limit."""
    ok = value <= limit if upper else value >= limit
    return {"value": float(value), "reference": float(limit), "rel_err": None, "tol": float(limit),
            "passed": bool(ok), "source": source}


def within(value: float, low: float, high: float, source: str, tol: float | None = None) -> dict:
    """Range check low <= value <= high (an observed band; a non-finite value fails); tol: the
    relative tolerance the band was widened by, as the case file gives it (it read the band's
    width, in the quantity's units)."""
    ok = math.isfinite(value) and low <= value <= high
    return {"value": float(value) if math.isfinite(value) else None, "reference": [float(low), float(high)],
            "rel_err": None, "tol": None if tol is None else float(tol), "passed": bool(ok), "source": source}


def energy_balance(history: dict, limit: float = 0.02) -> dict:
    """The ledger at the end of a run: |external work - (kinetic + internal + dissipated)|
    relative to the largest energy, at most ``limit``."""
    return bound(abs(float(history["balance_error_rel"][-1])), limit,
                 "energy ledger: external work = kinetic + internal + dissipated")


def relative_difference(x, ref) -> float | str:
    """|x - ref| / |ref|, or why no such number exists: a quantity not reached (nan or None) in
    one run or both, or ref = 0 beside another value (0 when both are 0). bench and compare
    report the reason where a number would mislead (nan, or a 0 when ref was 0)."""
    reached = lambda v: isinstance(v, numbers.Real) and math.isfinite(v)
    if not reached(x) or not reached(ref):
        return ("reached in neither run" if not reached(x) and not reached(ref) else
                "not reached in this run" if not reached(x) else "not reached in the reference")
    if ref == 0:
        return 0.0 if x == 0 else "0 in the reference"
    return abs(x - ref) / abs(ref)
