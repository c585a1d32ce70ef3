"""Checks against closed forms, recorded in the summary.json "checks" format."""
from __future__ import annotations


def check(value: float, reference: float, tol: float, source: str) -> dict:
    """Relative-error check |value - reference| / |reference| <= tol."""
    rel = abs(value - reference) / abs(reference) if reference else abs(value)
    return {"value": float(value), "reference": float(reference), "rel_err": float(rel),
            "tol": float(tol), "passed": bool(rel <= tol), "source": source}


def bound(value: float, limit: float, source: str, upper: bool = True) -> dict:
    """One-sided check value <= limit (upper) or value >= limit."""
    ok = value <= limit if upper else value >= limit
    return {"value": float(value), "reference": float(limit), "rel_err": None, "tol": float(limit),
            "passed": bool(ok), "source": source}
