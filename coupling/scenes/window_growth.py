"""A specimen's DEM window that grows ahead of its crack during the run (``zone.grow = true``
on dcb, enf and mixed_mode; coupling/study/growth.py grows the studies' zones the same way).

The window [x_a, x_b] starts at the initial crack tip a0, or a bending specimen's load line
ahead of it, plus the lead (zone.margin, or 4 arm thicknesses: ``lead``), or at dem.window_end.
At each FEM step (zone.grow_every: 1, or every so many steps and at the history samples) Hashin's interlaminar index on
the crack plane, (<s_n> / Z0)^2 + (t_s / R0)^2 with the strengths the particles' law
uses, is evaluated on both sides of the window's end: on the centroid stress of the intact FEM
band's elements ahead of it, and on the window's crack-plane bonds (their last tractions, or
any damage: the cohesive zone). Wherever it reaches zone.grow_at closer than the lead to x_b,
the window grows to the lead beyond it, to the next line of the band's mesh (every
mesh.element_length, rounded to whole particle spacings), at most to geometry.length - 4 h
(where beam theory's arms lose their built-in root). The conversion is the studies' (Growth):
the band's elements become the window's four rows, positions and velocities from the FEM
field, the lattice's rest lengths (so the particles carry the band's strain), momentum exact.
A growing window's lattice springs are law bonds (an engine's bonds take their rest lengths
from the positions it is built with, which are strained by then); on a fixed window they give
the engine's springs' results (dcb_coarse: the same peak load to 5 digits).

The window grows by whole mesh lines, and the band's FEM elements are meshed on them from the
start (``reserve``), so a grown model's FEM is the old mesh less the band's elements it took.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from physics.kernels import cohesive_reach

from ..params import CaseError, Param
from ..study.fields import ElementIndex
from ..study.growth import Growth
from . import delamination as dl

PARAMETERS: dict[str, Param] = {
    "zone.grow": Param(False, "grow the DEM window ahead of the crack during the run: the FEM band's elements "
                       "within zone.margin of where the interlaminar index reaches zone.grow_at become particles, "
                       "their state carried over (window_growth.py)", kind="bool"),
    "zone.grow_at": Param(0.25, "zone.grow: Hashin's interlaminar index (1 at initiation) on the crack plane, "
                          "in the FEM band ahead of the window or on its particles, that the window keeps zone.margin "
                          "ahead of", low=0.05, high=2.0),
    "zone.grow_every": Param(1, "zone.grow: the growth is checked every this many clock steps (1: each FEM step) "
                             "and at each history sample; 0: at the samples only (about 1000 a run, "
                             "output.history_every). A conversion a check between samples asks for comes at the next "
                             "step; checked every step, dcb_coarse and enf_coarse ran 1.05-1.10 x slower on LIGGGHTS "
                             "than at the samples",
                             kind="int", low=0),
    "zone.margin": Param(0.0, "zone.grow: how far the window reaches beyond where the index reaches zone.grow_at; "
                         "0: 4 arm thicknesses", unit="m", low=0.0),
    "dem.window_end": Param(0.0, "x of the DEM window's end; 0: the closed form's crack path and beyond it the "
                            "larger of dem.margin and the cohesive zone (dcb; enf and mixed_mode: at least the load "
                            "line plus dem.margin); with zone.grow, where it starts (0: a0 plus zone.margin)", unit="m", low=0.0),
    "dem.window_start": Param(0.0, "x of the DEM window's start; 0: the case's (dcb: dem.margin behind a0; enf and "
                              "mixed_mode: the specimen's end); beyond a0: the FEM band from a0 to it is a cohesive "
                              "interface (node pairs at the particle spacing, the same law), so the crack starts in "
                              "the FEM and runs on into the particles", unit="m", low=0.0),
}


@dataclass
class Window:
    """What Growth reads of a specimen's coupled model (the studies' assemble.Built)."""

    clock: object
    backend: object
    dyn: object
    lattice: object  # the DemScene: x (n, 3) m, the reference positions
    models: tuple
    inter: object  # the crack plane's LawBonds
    t: float  # the particle spacing, m
    fem_pairs: None = None
    bonded: None = None
    impactors: dict = field(default_factory=dict)


def window_of(spec: dl.Specimen) -> Window:
    clock = spec.clock
    return Window(clock, clock.dem, clock.fem, spec.scene, tuple(clock.models), spec.bonds, spec.t)


def lead(p: dict) -> float:
    """m, how far the growing window reaches ahead of the cohesive zone: zone.margin, or 4 arm
    thicknesses. The window's lattice is a little stiffer than the band it replaces (its tied
    rows reach half a spacing into the arms), and the arms bend over the crack tip's elastic
    foundation for several h ahead of it: on dcb_coarse (h = 3 mm) a window ending 8 mm ahead
    of the initial crack put the peak load 0.8 % below the window that holds the whole crack
    path, 12 mm 0.44 %, 16 mm 0.05 %."""
    return p["zone.margin"] or 4 * p["geometry.arm_thickness"]


def window_end(p: dict, placed: float) -> float:
    """m, a fixed window's end: dem.window_end, refused (CaseError) unless beyond the initial
    crack tip and at most geometry.length - 4 h, or ``placed`` (the closed form's) when 0."""
    x_b = p["dem.window_end"]
    a0, limit = p["geometry.crack_length"], p["geometry.length"] - 4 * p["geometry.arm_thickness"]
    if x_b and not a0 < x_b <= limit * (1 + 1e-12):
        raise CaseError(f"dem.window_end = {x_b:g}: the DEM window must end beyond the initial crack tip and "
                        f"before the specimen's root; allowed {a0:.4g} < x <= geometry.length - 4 h = {limit:.4g} m, "
                        "or 0 (the closed form's)")
    return x_b or placed


def window_start(p: dict, placed: float, x_b: float) -> float:
    """m, the DEM window's start: dem.window_start, refused (CaseError) unless beyond the
    initial crack tip a0 and at least 4 particle spacings before the window's end x_b (m), or
    ``placed`` (the case's) when 0."""
    x_a, a0, d = p["dem.window_start"], p["geometry.crack_length"], p["zone.particle_size"]
    if not x_a:
        return placed
    if x_b - 4 * d <= a0:
        raise CaseError(f"dem.window_start = {x_a:g}: no start fits: the window ends at {x_b:.4g} m, within 4 "
                        f"particle spacings of the initial crack tip {a0:.4g} m; allowed: 0, or a later dem.window_end")
    if not a0 < x_a <= x_b - 4 * d * (1 - 1e-9):
        raise CaseError(f"dem.window_start = {x_a:g}: the DEM window must start beyond the initial crack tip and "
                        f"hold at least 4 particle spacings before its end; allowed {a0:.4g} < x <= "
                        f"{x_b - 4 * d:.4g} m (the window's end {x_b:.4g} m less 4 zone.particle_size), or 0")
    return x_a


def start_end(p: dict, x_a: float, load_lines: tuple[float, ...] = ()) -> float:
    """m, the growing window's first end: dem.window_end, or the lead beyond the initial crack
    tip a0 (or the window's start x_a m, when that is ahead of it) and beyond the load lines
    ahead of it (x m: a bending specimen's punch, on the crack's path), in whole spacings from
    x_a. A load line just past the window's end moves the peak load: enf_coarse at E11 = 40
    GPa, h = 4 mm, the window ending 3 mm short of the load line read 2.0 % above the one 4 mm
    past it, 24 mm past it 0.16 % below."""
    d, a0 = p["zone.particle_size"], p["geometry.crack_length"]
    x_b = window_end(p, max([a0, x_a] + [x for x in load_lines if x > a0]) + lead(p))
    return x_a + np.ceil((x_b - x_a) / d - 1e-9) * d


def growing(p: dict, dem: str, placed: float, model, load_lines: tuple[float, ...] = ()) -> "object":
    """The Simulation of a specimen whose window grows: model(p, x_a, x_b, reserve, start) ->
    the coupled (Simulation, Specimen) of the window [x_a, x_b] on the mesh ``reserve`` (see
    delamination.build_specimen), continued from ``start`` (None: from rest); x_a: where the
    window starts (window_start: dem.window_start, or the case's ``placed``), its end grows;
    load_lines: see start_end."""
    if p["coupling.tie"] != "kinematic":
        raise CaseError(f"coupling.tie = {p['coupling.tie']}: zone.grow needs the kinematic tie (a penalty tie's "
                        "springs would not carry over); allowed: kinematic")
    d, h, L = p["zone.particle_size"], p["geometry.arm_thickness"], p["geometry.length"]
    e = max(1, round((p["mesh.element_length"] or 2 * d) / d)) * d
    x_a = p["dem.window_start"] or placed
    x0 = start_end(p, x_a, load_lines)
    window_start(p, placed, x0)  # (refused before a0, or too close to the first end)
    limit = x0 + np.floor((L - 4 * h - x0) / e + 1e-9) * e
    if limit < x0:
        key = "dem.window_end" if p["dem.window_end"] else "dem.window_start" if p["dem.window_start"] else "zone.margin"
        raise CaseError(f"{key} = {p[key]:g}: the growing window would start at x = {x0:.4g} m, beyond "
                        f"geometry.length - 4 h = {L - 4 * h:.4g} m; allowed: a smaller {key}, or a longer specimen")
    reserve = (x0, float(limit), e)

    def make(x_b: float, q: dict, start=None):
        sim, spec = model(q, x_a, x_b, reserve, start)
        return sim, window_of(spec)

    sim, built = make(x0, p)
    WindowGrowth(make, p, dem, built, sim, reserve)
    return sim


class WindowGrowth(Growth):
    """A specimen's window as it grows (the studies' Growth, with the band's index as the
    criterion, the band's mesh lines as the steps, and no symmetry plane)."""

    symmetric = False
    limit_name = "geometry.length - 4 h"
    reach_name = "the cohesive zone"

    def __init__(self, make, p: dict, dem: str, built: Window, sim, reserve: tuple[float, float, float]):
        self._reserve = reserve
        super().__init__(make, p, dem, built, sim)

    def _extent(self, built):
        return built.t, self._reserve[1], lead(self.p)

    def _bind_criteria(self, built) -> None:
        region, h = built.dyn.region, self.p["geometry.arm_thickness"]
        c = region.X[region.mesh.t].mean(axis=0)  # (nel, 2) centroids
        x_b = float(built.lattice.x[:, 0].max())
        self._band = (np.abs(c[:, 1] - h) < built.t) & (c[:, 0] > x_b)  # the intact band ahead of the window
        self._strengths = Z0, R0 = dl.resolved_strengths(self.p, built.t)
        self._index = ElementIndex(region, self._plane_stress(region), False, self._band, None, Z0, R0)
        bonds = built.inter  # (x of each crack-plane bond's first particle: contact_reach)
        self._bond_x = np.ascontiguousarray(bonds.X[bonds.pairs[:, 0], 0], float)

    @staticmethod
    def _plane_stress(region):
        """strain (nel, 3) -> (nel, 6) Pa: the crack plane's normal stress s_yy as "33" and its
        shear s_xy as "13" (the plane's axes), the rest 0."""
        def stress(strain: np.ndarray) -> np.ndarray:
            s = np.einsum("est,et->es", region.D, strain)
            out = np.zeros((len(s), 6))
            out[:, 2], out[:, 4] = s[:, 1], s[:, 2]
            return out
        return stress

    def index(self, u: np.ndarray) -> np.ndarray:
        """(nel,) Hashin's interlaminar index on the crack plane of the band's elements ahead
        of the window (0 elsewhere), at FEM displacement u (n, 2) m (a buffer rewritten at
        each call)."""
        return self._index(u)

    def contact_reach(self) -> float:
        """m: the farthest crack-plane bond of the window whose interlaminar index reached
        zone.grow_at (the cohesive zone and what is about to join it), -1 if none: the window
        keeps its lead ahead of it (an unstable crack outruns the band's elements ahead)."""
        bonds = self.built.inter
        Z0, R0 = self._strengths
        return cohesive_reach(bonds.traction, bonds.normal, bonds.damage, self._bond_x, Z0, R0, self.grow_at)

    def _reaches(self, built) -> list:
        return []  # (damage_reach reads none: the crack-plane bonds are contact_reach's)

    def damage_reach(self) -> float:
        """-1: the window's crack-plane bonds are contact_reach's (their damage is the crack the
        window follows)."""
        return -1.0

    def snap(self, x: float) -> float:
        x0, _, e = self._reserve
        return x0 + np.ceil((x - x0) / e - 1e-9) * e

    def _assemble(self, x_b: float, start=None, error=CaseError):
        q = dict(self.p, **{"clock.dt": self.sim.dt, "clock.substeps": self.built.clock.m})
        try:
            return self.study(x_b, q, start)
        except CaseError as exc:
            raise error(f"zone.grow = true: the window grown to x = {x_b * 1e3:.4g} mm cannot be modelled "
                        f"({exc})") from None
