"""Where the particles go: a beam's DEM zone placed from an elastic estimate (``zone.placement
= "auto"``).

The estimate is the study's own all-FEM run (the cheap bound, no ply can fail in it) over the
run's duration. At every sample it records, per element, the largest failure index met so far,
Hoffman's ply index (when the zone's plies can fail) and Hashin's interlaminar index (when the
far field's plies are tied: a cohesive far field delaminates by itself), and the contact patch:
the farthest node any impactor pressed. The zone is the box about the impact that holds the
patch and every element reached from it whose index reaches ``zone.grow_at``: grown along x
from the patch over each such element that starts within ``zone.margin`` of the reach, then
widened by the margin and rounded up to whole particle spacings.

An element whose index reaches grow_at beyond the zone, with a gap wider than the margin
between (a clamp's bending, far from the impact), is left to the far field with a warning:
the FEM cannot fail there. A zone the box cannot hold (past 0.8 of the half span) is refused.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..params import CaseError
from .fields import FemIndices


@dataclass
class Placement:
    """A placed zone: half_width (m) and what decided it: the contact patch's reach (m), the
    flagged elements' reach (m), the estimate's largest index, its wall time (s), and one line
    per flagged region left outside."""

    half_width: float
    contact: float
    reach: float
    peak: float
    wall: float
    warnings: list[str] = field(default_factory=list)

    def qoi(self) -> dict[str, float]:
        return {"zone_half_width": self.half_width, "zone_contact_reach": self.contact,
                "zone_estimate_reach": self.reach, "zone_estimate_peak_index": self.peak,
                "zone_estimate_wall_s": self.wall}


def grown_reach(x0: np.ndarray, x1: np.ndarray, start: float, margin: float) -> float:
    """Reach (m) of the zone from x = 0: ``start`` grown over every element [x0, x1] (m, (n,)
    each, the flagged ones) that begins within ``margin`` of the reach so far."""
    from physics.kernels import flagged_reach  # (the growth's checks run the same rule over an index)
    x0, x1 = np.ascontiguousarray(x0, float), np.ascontiguousarray(x1, float)
    return float(flagged_reach(np.ones(len(x0)), np.argsort(x0, kind="stable"), x0, x1, 1.0, float(start),
                               float(margin)))


@dataclass
class Estimate:
    """What the all-FEM estimate found: each element's extent along x, x0 and x1 (nel,) m; the
    largest index each criterion reached in it, peaks {criterion: (nel,)}; the farthest node
    an impactor pressed, contact (m); its wall time (s)."""

    x0: np.ndarray
    x1: np.ndarray
    peaks: dict[str, np.ndarray]
    contact: float
    wall: float


def criteria(p: dict, built) -> list[str]:
    """The failure indices that put an element in the zone: Hoffman's when the zone's plies
    fail, Hashin's interlaminar when the far-field plies are tied (a cohesive far field
    delaminates by itself)."""
    return (["Hoffman"] if p["zone.ply_failure"] else []) + \
        (["interlaminar"] if built.fem_pairs is None or len(built.fem_pairs) == 0 else [])


def estimate(study, p: dict) -> tuple[Estimate, float, float, float]:
    """(Estimate, particle size d, half span L, laminate thickness H; m) of ``p``'s all-FEM
    run (a beam or beam_3d study) over the run's duration."""
    from ..simulation import Instability, run_clock
    from .assemble import beam

    if p.get("mesh.file"):  # the placed edge would have to be a line of the file's mesh
        raise CaseError("zone.placement = 'auto': not with a mesh file (mesh.file), whose line at the zone's edge "
                        "fixes the zone; allowed: zone.placement = 'box'")
    q = dict(p, **{"clock.dt": 0.0, "output.field_frames": 0})
    t0 = time.perf_counter()
    sim, built = beam(study, q, "fem", "")
    dyn, region = built.dyn, built.dyn.region
    indices = FemIndices(region, built.lam, built.dim)
    peaks = {c: np.zeros(region.n_elements) for c in criteria(p, built)}
    contact = [0.0]

    def track() -> float:
        hashin, hoffman = indices(region.centroid_strain_stress(dyn.state.u)[0])
        for c, now in (("Hoffman", hoffman), ("interlaminar", hashin)):
            if c in peaks:
                np.maximum(peaks[c], now, out=peaks[c])
        x = region.X + dyn.state.u
        for imp in dyn.impactors:
            pressed = imp.gap(x)[0] > 0
            if pressed.any():
                contact[0] = max(contact[0], float(region.X[pressed, 0].max()))
        return 0.0

    sim.probes = {"placement": track}
    sim.history_every = max(1, sim.n_steps // 4000)  # peaks under an impact last microseconds
    try:
        run_clock(sim)
    except Instability as exc:
        raise CaseError(f"zone.placement = 'auto': the all-FEM estimate stopped ({exc}); allowed: zone.placement = "
                        "'box' with a zone.half_width") from None
    finally:
        sim.close()
    X = region.X[region.mesh.t.T][:, :, 0]  # (nel, nodes) x of each element's nodes
    return Estimate(X.min(axis=1), X.max(axis=1), peaks, contact[0], time.perf_counter() - t0), built.t, \
        built.half_span, built.lam.thickness


def decide(est: Estimate, d: float, L: float, grow_at: float, margin: float, punch: float = 0.0,
           far_field: str = "") -> Placement:
    """The zone from an estimate: the box about the impact holding the contact patch (or a
    punch's face, half width ``punch`` m, and two particles beyond) and every element reached
    from it whose index reaches ``grow_at``, plus ``margin`` (m), in whole particle spacings
    d (m). Refused (CaseError) when that is not below 0.8 L (the half span, m);
    ``far_field``: the setting that lets a tied far field delaminate, named in the refusal."""
    flagged_by = list(est.peaks)
    index = np.max([est.peaks[c] for c in flagged_by], axis=0) if flagged_by else np.zeros(len(est.x0))
    flagged = index >= grow_at
    start = max(est.contact, punch)
    reach = grown_reach(est.x0[flagged], est.x1[flagged], start, margin)
    w = max(np.ceil((reach + margin) / d - 1e-9), np.ceil((punch + 2 * d) / d - 1e-9), 3) * d
    if not w < 0.8 * L:
        allowed = f"allowed at most 0.8 x half the span ({0.8 * L * 1e3:.3g} mm)"
        if reach <= start or not flagged_by:  # the patch (or punch) and the margin alone
            raise CaseError(f"zone.placement = 'auto': the contact patch ({start * 1e3:.3g} mm) and the margin "
                            f"({margin * 1e3:.3g} mm) make the zone {w * 1e3:.3g} mm; {allowed}: a smaller "
                            "zone.margin, or --mode dem")
        near = flagged & (est.x0 <= reach)
        which = max(flagged_by, key=lambda c: est.peaks[c][near].max(initial=0.0))
        raise CaseError(
            f"zone.placement = 'auto': the all-FEM estimate puts the {which} index at {grow_at:g} or more from the "
            f"impact out to x = {reach * 1e3:.3g} mm, so the zone would be {w * 1e3:.3g} mm; {allowed}: raise "
            "zone.grow_at, or run --mode dem"
            + (f", or let the far field delaminate ({far_field})" if far_field and which == "interlaminar" else ""))
    out = flagged & (est.x1 > w + 1e-9 * L)
    warnings = []
    for c in flagged_by:
        beyond = out & (est.peaks[c] >= grow_at)
        if beyond.any():
            k = np.flatnonzero(beyond)[np.argmax(est.peaks[c][beyond])]
            warnings.append(f"zone.placement = 'auto': the all-FEM estimate puts the {c} index at {est.peaks[c][k]:.2f} "
                            f"at x = {0.5 * (est.x0[k] + est.x1[k]) * 1e3:.3g} mm, beyond the zone ({w * 1e3:.3g} mm) "
                            "and not reached from the impact: the far field cannot fail there (--mode dem shows it)")
    return Placement(float(w), float(est.contact), float(reach), float(index.max(initial=0.0)), est.wall, warnings)


def place(study, p: dict, estimated: tuple) -> Placement:
    """The zone of the coupled run of ``p`` (a beam or beam_3d study) from its all-FEM estimate
    ``estimated`` (what ``estimate`` returns)."""
    est, d, L, H = estimated
    # a contact's own stress field decays over about the laminate's thickness (Saint-Venant):
    # the tie stays outside it (a 4-particle margin let the coupled beam crack plies at its edge)
    margin = p["zone.margin"] or max(4 * d, H)
    punch = max((p.get(f"impactors.{n}.half_width", 0.0) for n in study.layout.names["impactors"]), default=0.0)
    far_field = f"laminates.{p['geometry.laminate']}.far_field_interfaces = 'cohesive'"
    return decide(est, d, L, p["zone.grow_at"], margin, punch, far_field)
