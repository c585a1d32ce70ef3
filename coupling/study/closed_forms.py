"""The closed-form registry: what a study's checks compare with, by
``[checks.NAME] closed_form = "..."``. Each form computes its reference from the run's own
parameters (never from a previous run) and names the qoi it records it as."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..checks import check, energy_balance
from ..params import Param
from .schema import section

_CHECK = {"qoi": Param("", "the qoi compared (a name the run reports)", kind="str"),
          "tol": Param(0.05, "relative tolerance", low=0.0, open_low=True, high=10.0)}


@dataclass(frozen=True)
class ClosedForm:
    doc: str
    reference_qoi: str  # the qoi the reference is recorded as
    reference: Callable  # (study, p) -> float, SI
    source: str
    fields: dict = None

    def __post_init__(self):
        object.__setattr__(self, "fields", dict(_CHECK))


def beam_spring_mass(study, p: dict) -> float:
    """Peak centre deflection (m) of a beam struck at mid-span by a rigid mass: v sqrt(M / k),
    quasi-static stiffness k = 192 D / L^3 clamped or 48 D / L^3 simply supported (L the span,
    D the plane-strain bending stiffness per width), M the impactor's mass plus the beam's
    effective mass, 0.37 (clamped, Rayleigh's 13/35) or 17/35 (simply supported) of its own."""
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    (support,) = study.layout.names["supports"]
    clamped = p[f"supports.{support}.fix"] == "xy"
    span = p["geometry.span"]
    k = (192 if clamped else 48) * lam.bending_stiffness() / span**3
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    M = q["mass_per_width"] + (0.37 if clamped else 17 / 35) * lam.ply["rho"] * lam.thickness * span
    return q["velocity"] * np.sqrt(M / k)


CLOSED_FORMS: dict[str, ClosedForm] = {
    "beam_spring_mass": ClosedForm(
        "spring-mass estimate of a beam's peak deflection under a central impact (one impactor, one support "
        "kind at both ends)", "spring_mass_estimate", beam_spring_mass,
        "spring-mass estimate v sqrt(M / k), k = 192 D / L^3 (clamped) or 48 D / L^3 (simply supported)"),
}


def evaluate(study, p: dict, qoi: dict, history: dict) -> dict:
    """The study's checks, plus the energy balance every run has; records each reference as qoi."""
    checks = {}
    for name, form_name in study.layout.names["checks"].items():
        form, f = CLOSED_FORMS[form_name], section(p, f"checks.{name}")
        ref = qoi[form.reference_qoi] = form.reference(study, p)
        if f["qoi"] in qoi:
            checks[name] = check(qoi[f["qoi"]], ref, f["tol"], form.source)
    checks["energy_balance"] = energy_balance(history)
    return checks
