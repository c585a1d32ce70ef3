"""A zone that grows during the run (issue #25, part 2; coupling/study/growth.py), 2D and 3D beams
and bonded beams.

The coarse seed beam struck at 12 m/s from a 3 mm zone, growing where the far field's Hoffman
index reaches 0.12 (a low threshold, so that the stress wave converts elements early and
often): each conversion keeps the momentum to round-off and the beam's mass exactly, the zones
are whole particle spacings that only grow, the zone's edge never damages, every far-field
element the criterion flags ends inside the zone, and a run resumed from a checkpoint taken
after a conversion finishes as the uninterrupted one, bit for bit. The coarse CFRP-strengthened
concrete beam (seed 5.4) grows from its hand-drawn 3 in zone, whose edge cracks, as its concrete's
Hoffman index spreads along the span."""
import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from conftest import SEED_CASES, ranged_draw, set_args, verified
from coupling.case import load_case
from coupling.simulation import run_clock

GROW = {"zone.grow": True, "zone.half_width": 3e-3, "impactors.cylinder.velocity": 12.0, "zone.grow_at": 0.12}
GROW_3D = {"zone.grow": True, "zone.half_width": 1.8e-3, "impactors.cylinder.velocity": 12.0,
           "laminates.beam.far_field_interfaces": "cohesive"}


def _sets(values: dict) -> list[str]:
    return [f"--set={k}={str(v).lower() if isinstance(v, bool) else v}" for k, v in values.items()]


def test_a_growing_zone_keeps_momentum_and_mass_and_only_grows(femdem, tmp_path):
    """LIGGGHTS, 15 us of the impact (three conversions as the wave runs out)."""
    code, s, err = femdem("run", "beam_impact_coarse", "--dem", "liggghts", *_sets(GROW),
                          "--set=clock.t_end=1.5e-5", "--set=output.field_frames=6", "--set=output.history_every=7")
    assert code == 0, err
    q = s["qoi"]
    assert q["zone_conversions"] >= 2
    with h5py.File(tmp_path / "run0" / "history.h5") as h:
        g = h["history"]
        jumps_P, jumps_E = g["zone.conversion_momentum_jump"][:], g["zone.conversion_energy_jump"][:]
        widths, series = g["zone.conversion_half_width"][:], g["zone_half_width"][:]
        kinetic, steps = g["kinetic"][:], s["clock"]["steps"]
    d = 2 * 0.15e-3  # two plies per particle row
    assert len(jumps_P) == len(jumps_E) == len(widths) == q["zone_conversions"]
    assert np.all(jumps_P < 1e-12)  # the converted particles take up what the new split of the mass changed
    assert np.all(np.abs(jumps_E) < 1e-2)  # reported (the elements' against the bonds' energy; docs/status.md)
    assert np.all(np.diff(np.concatenate([[3e-3], widths])) > 0)
    assert np.allclose(widths / d, np.round(widths / d), atol=1e-6)
    assert np.all(np.diff(series) >= 0) and series[-1] == pytest.approx(q["zone_grown_half_width"])
    assert q["damage_at_zone_edge"] == 0.0
    # the last sample (a step no multiple of the sampling's) is the grown model's last step's
    assert steps % 7 and kinetic[-1] != kinetic[-2]
    # one XDMF per zone: the frames before the first conversion, then each zone's that took one
    assert (tmp_path / "run0" / "fields.xdmf").exists() and (tmp_path / "run0" / "fields-1.xdmf").exists()
    assert (tmp_path / "run0" / "plots" / "zone.png").exists()


@pytest.mark.parametrize("name, sets", [
    ("beam_impact_coarse", dict(GROW, **{"clock.t_end": 1.2e-5})),
    # a 3D quarter with a cohesive far field, grown by the contact (its index stays low so early)
    ("beam_impact_3d_coarse", dict(GROW_3D, **{"clock.t_end": 1e-5}))])
def test_the_grown_model_holds_the_beam_s_mass_and_covers_what_the_criterion_flags(name, sets):
    """In process (LIGGGHTS): every conversion keeps the momentum to round-off; after the run
    the far field's nodes and the free particles carry the modelled part's mass exactly (the
    slice rho L H t in 2D, the quarter rho L W H / 2 in 3D; the interface particles' masses are
    in the nodes); no far-field element left reaches grow_at."""
    case = load_case(name, sets)
    study, p = case.scene, case.parameters
    sim = study.build(p, "coupled", "liggghts")
    try:
        result = run_clock(sim)
    finally:
        sim.close()
    growth = study.growth
    assert result["simulation"] is growth.sim and growth.events
    built, clock = growth.built, growth.built.clock
    free = clock.tie.free_particles(built.lattice.n).astype(bool)
    lam, d = built.lam, built.t
    assert all(e[3] < 1e-12 for e in growth.events)
    mass = built.dyn.m.sum() + clock.dem.scene.mass[free].sum()
    across = d if built.dim == 2 else 0.5 * p["geometry.width"]
    assert mass == pytest.approx(lam.ply["rho"] * 0.5 * p["geometry.span"] * lam.thickness * across, rel=1e-12)
    hashin, hoffman = growth._indices(built.dyn.region.centroid_strain_stress(clock.u_snapshot)[0])
    assert hoffman.max() < p["zone.grow_at"]


def test_a_zone_checked_at_every_fem_step_converts_between_samples():
    """zone.grow_every = 1 (the issue's "each FEM step"): a check takes the FEM's state only and
    evaluates the compiled criterion; when the zone must grow it converts at the next step,
    where the clock takes its whole snapshot. The coarse beam struck at 12 m/s from 3 mm,
    samples every 50 steps: conversions between samples, momentum to round-off, whole spacings
    that only grow, no damage at the zone's edge, and its first conversion no later than with
    checks at the samples only (the two runs are one until then, and a check at every step sees
    every sample's state)."""
    def grown(every: int):
        case = load_case("beam_impact_coarse", dict(GROW, **{"clock.t_end": 1.5e-5, "zone.grow_every": every,
                                                              "output.history_every": 50}))
        sim = case.scene.build(case.parameters, "coupled", "liggghts")
        try:
            return run_clock(sim), case.scene.growth
        finally:
            case.scene.growth.sim.close()

    sampled = grown(0)
    result, growth = grown(1)
    steps = np.array([e[0] for e in growth.events]) / growth.sim.dt
    assert len(steps) >= 2 and np.any(np.abs(steps / 50 - np.round(steps / 50)) > 1e-6), steps
    assert all(e[3] < 1e-12 for e in growth.events)
    d = 2 * 0.15e-3
    widths = np.array([e[1] for e in growth.events])
    assert np.all(np.diff(np.concatenate([[3e-3], widths])) > 0) and np.allclose(widths / d, np.round(widths / d))
    assert max(result["history"]["damage_at_zone_edge"]) == 0.0
    assert growth.events[0][0] <= sampled[1].events[0][0] + 1e-6 * growth.sim.dt


@pytest.mark.parametrize("engine", ["liggghts", "yade", "lammps"])
def test_a_check_reads_the_impactor_s_contact_without_calling_the_engine(engine):
    """The contact reach of a check reads the candidates' positions the impactor model kept at
    its last evaluation (ParticleImpactor.last_positions, no call to an engine's worker): they
    are the engine's positions between steps, on every engine (LAMMPS in its worker, its models
    synced), and some candidate touches by then."""
    case = load_case("beam_impact_coarse", dict(GROW, **{"clock.t_end": 4e-6, "zone.half_width": 6e-3}))
    sim = case.scene.build(case.parameters, "coupled", engine)
    try:
        run_clock(sim)
        growth = case.scene.growth
        if sim.sync is not None:
            sim.sync()
        for m in growth.built.impactors.values():
            assert np.array_equal(m.last_positions(), growth.built.backend.positions_of(m.ids))
        assert growth.contact_reach() >= 0.0
    finally:
        case.scene.growth.sim.close()


def test_damage_the_far_field_cannot_take_is_reported(femdem, tmp_path):
    """The coarse beam struck at 12 m/s, grown from 0.9 mm, to 120 us: the far field is meshed
    at the particle spacing out to grow_to, and near the clamp (x 19-24 mm, beyond grow_to =
    20 mm) its 90 plies reach Hoffman's index 1 where the all-DEM beam's 90 plies crack (at 20.3,
    22.1 and 23.6 mm by 0.6 ms, docs/benchmarks.md session 38). The run says so in one warning
    line, printed and in the summary, naming where (the x of the history's peak) and when (the
    first sample at 1); the qoi hold the peak and its place. A run whose far field stays below 1
    (the hand-drawn 12 mm zone fixed, struck at 8 m/s: no interface debonds by 120 us, the index
    about 0.2) says nothing of it. (At 12 m/s the hand-drawn zone's far field, no element finer
    than the particles since session 43, debonds the upper interface over 28.2 mm as all-DEM does,
    and its 90 plies then pass 1 near the clamp too.)"""
    sets = ["--set=zone.grow=true", "--set=zone.half_width=0.9e-3", "--set=impactors.cylinder.velocity=12",
            "--set=clock.t_end=1.2e-4"]
    code, s, err = femdem("run", "beam_impact_coarse", *sets)
    assert code == 0, err
    q = s["qoi"]
    lines = [w for w in s["warnings"] if w.startswith("the far field's Hoffman ply index reached 1")]
    assert q["peak_far_field_hoffman"] >= 1.0 and len(lines) == 1, s["warnings"]
    assert f"{q['peak_far_field_hoffman']:.2f} at most" in lines[0]
    assert f"x = {q['x_of_peak_far_field_hoffman'] * 1e3:.3g} mm" in lines[0]
    assert 0.019 < q["x_of_peak_far_field_hoffman"] < 0.025  # near the clamp, beyond grow_to
    assert f"femdem: warning: {lines[0]}" in err
    with h5py.File(tmp_path / "run0" / "history.h5") as h:
        t, index = h["history"]["time"][:], h["history"]["far_field_hoffman"][:]
    assert f"t = {t[np.argmax(index >= 1.0)]:.3g} s" in lines[0]
    code, s, err = femdem("run", "beam_impact_coarse", "--set=impactors.cylinder.velocity=8", "--set=clock.t_end=1.2e-4")
    assert code == 0, err
    assert s["qoi"]["peak_far_field_hoffman"] < 1.0 and not any("far field's" in w for w in s["warnings"])


def _resumed_as_straight(tmp_path, name: str, sets: dict, dem: str, at: float):
    """A run that checkpoints once, at the fraction ``at`` of its steps, after its zone grew, and
    the run resumed from that checkpoint in a new model (the first zone's, rebuilt to the
    checkpoint's): their histories, bit for bit."""
    from coupling import checkpoint
    case = load_case(name, sets)
    study, p = case.scene, case.parameters

    def run(**kw):
        sim = study.build(p, "coupled", dem)
        try:
            if "run_dir" in kw:
                kw["checkpoint_every"] = int(at * sim.n_steps)
            return run_clock(sim, **kw), study.growth
        finally:
            sim.close()

    # the uninterrupted run writes its checkpoint as it goes
    straight, growth = run(run_dir=tmp_path)
    ck = checkpoint.latest(tmp_path)
    assert checkpoint.read(ck)["loop"]["growth"]["half_width"] > p["zone.half_width"]
    assert growth.events[0][0] < checkpoint.step_of(ck) * growth.sim.dt
    resumed, _ = run(resume_from=ck)
    for k, v in straight["history"].items():
        assert np.array_equal(v, resumed["history"][k], equal_nan=True), k


@pytest.mark.slow  # 19 s (the suite's ten minutes, session 44): the suite resumes grown zones on
# LIGGGHTS (the bonded beam, the disc, the window, a released reserve) and LAMMPS' hosted laws
# (tests/test_resume_cases.py)
def test_a_run_resumed_after_a_conversion_finishes_as_the_uninterrupted_one(tmp_path):
    """LAMMPS (its laws in the worker), the checkpoint at two thirds of the run."""
    _resumed_as_straight(tmp_path, "beam_impact_coarse", dict(GROW, **{"clock.t_end": 9e-6}), "lammps", 2 / 3)


@pytest.mark.parametrize("sets, key", [
    ({"zone.grow_to": 30e-3}, "zone.grow_to"),
    ({"zone.grow_to": 2.4e-3}, "zone.grow_to"),
    ({"coupling.tie": "penalty"}, "coupling.tie"),
])
def test_bad_growth_settings_are_refused(femdem, sets, key):
    code, s, err = femdem("run", "beam_impact_coarse", *_sets(dict(GROW, **sets)))
    assert code == 2 and key in err and "allowed" in err and s is None


CFRP = {"zone.grow": True}


@pytest.mark.slow  # 43 s, two runs (the suite's ten minutes, session 44): the suite grows the bonded
# beam anywhere in its ranges and resumes it across a conversion (below)
def test_a_bonded_beam_s_zone_grows_ahead_of_its_cracks(femdem, tmp_path):
    """cfrp_beam_impact_coarse (LIGGGHTS): the case's 3 in zone cracks at its edge; grown from it,
    no damage ever reaches the zone's edge, the conversions keep the momentum to round-off, the
    zones are whole spacings that only grow, and the peak mid-span deflection is within 1 % of
    the run with the final zone fixed from t = 0."""
    code, fixed_small, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", "liggghts")
    assert code == 0, err
    assert fixed_small["qoi"]["damage_at_zone_edge"] > 0.5  # (why it must grow)
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", "liggghts", *_sets(CFRP))
    assert code == 0, err
    q = s["qoi"]
    with h5py.File(tmp_path / "run1" / "history.h5") as h:
        g = h["history"]
        jumps_P, widths, edge = g["zone.conversion_momentum_jump"][:], g["zone.conversion_half_width"][:], \
            g["damage_at_zone_edge"][:]
    d = 3.81e-3
    assert q["zone_conversions"] >= 1 and np.all(jumps_P < 1e-12)
    assert np.all(np.diff(np.concatenate([[0.0762], widths])) > 0)
    assert np.allclose(widths / d, np.round(widths / d), atol=1e-6)
    assert np.all(edge == 0.0)
    code, final, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", "liggghts",
                              f"--set=zone.half_width={q['zone_grown_half_width']}")
    assert code == 0, err
    assert final["counts"]["particles"] == s["counts"]["particles"]
    want = final["qoi"]["peak_midspan_displacement"]
    assert abs(q["peak_midspan_displacement"] / want - 1) < 0.01


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["yade", "lammps"])
def test_a_bonded_beam_s_zone_grows_on_every_engine(femdem, tmp_path, engine):
    """The coarse CFRP beam grown from its 3 in zone on the other engines: conversions that keep
    the momentum to round-off, no damage at the zone's edge at any sample, and the peak mid-span
    deflection within 1 % of the grown run on LIGGGHTS (the engines integrate alike)."""
    peaks = []
    for dem in ("liggghts", engine):
        code, s, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", dem, *_sets(CFRP))
        assert code == 0, err
        q = s["qoi"]
        assert q["zone_conversions"] >= 1 and q["zone_conversion_momentum_jump"] < 1e-12
        assert q["damage_at_zone_edge"] == 0.0
        peaks.append(q["peak_midspan_displacement"])
    assert abs(peaks[1] / peaks[0] - 1) < 0.01, peaks


@pytest.mark.parametrize("name", ["cfrp_beam_impact_coarse", "cfrp_beam_impact_3d_coarse"])
def test_a_grown_bonded_beam_holds_its_mass_and_its_bonds_strengths(name):
    """In process (LIGGGHTS), to the first conversion's aftermath: the far field's nodes and the
    free particles carry the modelled part's mass exactly (concrete and sheet: (rho_c H + rho_s
    t_s) L / 2 per unit width, times the slice's thickness d or half the width); each concrete
    bond the grown zone kept has the strength it had (the scatter is keyed by where a bond is);
    no far-field element left reaches grow_at."""
    case = load_case(name, dict(CFRP, **{"clock.t_end": 1.8e-4}))
    study, p = case.scene, case.parameters
    sim = study.build(p, "coupled", "liggghts")
    first = study.growth.built.intra
    try:
        run_clock(sim)
    finally:
        sim.close()
    growth = study.growth
    assert growth.events and all(e[3] < 1e-12 for e in growth.events) and not growth.limit_warning
    built, clock = growth.built, growth.built.clock
    bb, d = built.bonded, built.t
    free = clock.tie.free_particles(built.lattice.n).astype(bool)
    mass = built.dyn.m.sum() + clock.dem.scene.mass[free].sum()
    across = d if built.dim == 2 else 0.5 * p["geometry.width"]
    want = (bb.body["rho"] * bb.depth + bb.sheet["rho"] * bb.ts) * 0.5 * bb.length * across
    assert mass == pytest.approx(want, rel=1e-12)
    grown = built.intra
    key = lambda b: {tuple(np.round(b.X[i] / d, 6)) + tuple(np.round(b.X[j] / d, 6)): k
                     for k, (i, j) in enumerate(b.pairs)}
    old, new = key(first), key(grown)
    common = [(old[k], new[k]) for k in old if k in new]
    assert len(common) > 0.9 * len(old)
    i, j = np.array(common).T
    assert np.array_equal(first.law.strength_scale[i], grown.law.strength_scale[j])
    hashin, hoffman = growth._indices(built.dyn.region.centroid_strain_stress(clock.u_snapshot)[0])
    assert max(hashin.max(), hoffman.max()) < p["zone.grow_at"]


def test_a_bonded_beam_resumed_after_a_conversion_finishes_as_the_uninterrupted_one(tmp_path):
    """LIGGGHTS in process, the checkpoint at three quarters of the run (after the first
    conversion, 158 us)."""
    _resumed_as_straight(tmp_path, "cfrp_beam_impact_coarse", dict(CFRP, **{"clock.t_end": 2.4e-4}), "liggghts", 0.75)


def _bonded_grows(femdem, tmp_path, sets: list, dem: str) -> None:
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", dem, "--set=zone.grow=true", *sets)
    assert code == 0, err
    q = s["qoi"]
    assert s["checks"]["energy_balance"]["passed"], s["checks"]["energy_balance"]
    assert q["zone_conversions"] >= 1  # (the concrete's index spreads from the zone's edge within 0.45 ms)
    assert q["zone_conversion_momentum_jump"] < 1e-12
    runs = sorted(tmp_path.glob("run*"), key=lambda d: d.stat().st_mtime)
    with h5py.File(runs[-1] / "history.h5") as h:
        widths, series = h["history"]["zone.conversion_half_width"][:], h["history"]["zone_half_width"][:]
    assert np.all(np.diff(widths) > 0) and np.all(np.diff(series) >= 0)
    assert np.allclose(widths / 3.81e-3, np.round(widths / 3.81e-3), atol=1e-6)
    if not [w for w in s["warnings"] if "grows no further" in w]:  # (at its limit the far field may go on)
        assert q["damage_at_zone_edge"] == 0.0


@settings(max_examples=1, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # (one draw: the suite's budget)
@given(sets=ranged_draw("cfrp_beam_impact_coarse"))
def test_a_bonded_beam_grows_anywhere_in_its_ranges(femdem, tmp_path, sets):
    """Grown from the case's zone anywhere in its [ranges] (every key drawn at once, to 0.45 ms
    of the load): it grows, the ledger closes, the momentum to round-off at each conversion, zones in
    whole spacings that only grow, and no damage at the zone's edge unless it reached its limit."""
    _bonded_grows(femdem, tmp_path, sets, "liggghts")


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(dem=st.sampled_from(["liggghts", "lammps", "yade"]), sets=ranged_draw("cfrp_beam_impact_coarse"))
def test_a_bonded_beam_grows_anywhere_in_its_ranges_on_every_engine(femdem, tmp_path, dem, sets):
    """The same, six random draws over the three engines (-m slow)."""
    _bonded_grows(femdem, tmp_path, sets, dem)


def test_a_zone_narrower_than_its_margin_waits_for_a_reason_to_grow(femdem):
    """A bonded beam's 1.5 in zone (its margin, the beam's depth, is twice that) under the load's
    first 20 us: no element near its edge reaches grow_at and nothing touches it, so it stays."""
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", "liggghts",
                          *_sets(dict(CFRP, **{"zone.half_width": 0.0381, "clock.t_end": 2e-5})))
    assert code == 0, err
    assert s["qoi"]["zone_conversions"] == 0


@pytest.mark.parametrize("sets, key", [
    ({"zone.grow_to": 0.36}, "zone.grow_to"),
    ({"zone.grow_to": 0.05}, "zone.grow_to"),
    ({"coupling.tie": "penalty"}, "coupling.tie"),
])
def test_bad_bonded_growth_settings_are_refused(femdem, sets, key):
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", *_sets(dict(CFRP, **sets)))
    assert code == 2 and key in err and "allowed" in err and s is None


PLATE = {"zone.grow": True, "zone.half_width": 2.5e-3, "impactors.ball.velocity": 2.5}


def _plate():
    from pathlib import Path
    return Path(__file__).parent / "studies" / "clamped_plate.toml"


def _grown_square(case: str, sets: dict):
    """(parameters, Growth, the first zone's FEM region) of ``case`` with ``sets`` run in process
    on LIGGGHTS, once asserted: each conversion kept the momentum to round-off, and the zone is
    a square of whole particle spacings."""
    c = load_case(case, sets)
    study, p = c.scene, c.parameters
    sim = study.build(p, "coupled", "liggghts")
    region0 = study.growth.built.dyn.region
    try:
        run_clock(sim)
    finally:
        sim.close()
    growth = study.growth
    assert growth.events and all(e[3] < 1e-12 for e in growth.events)
    d, x, w = growth.built.t, growth.built.lattice.x, growth.half_width
    assert abs(w / d - round(w / d)) < 1e-6
    assert x[:, 0].max() == pytest.approx(w) and x[:, 1].max() == pytest.approx(w)
    return p, growth, region0


@pytest.mark.slow  # 27 s (the suite's ten minutes, session 44): the suite grows the same square
# zone in the rod's disc (test_a_disc_s_square_zone_grows_keeping_momentum_and_mass)
def test_a_plate_s_square_zone_grows_keeping_momentum_and_mass():
    """The clamped cross-ply plate (tests/studies/clamped_plate.toml) struck at 2.5 m/s from a
    2.5 mm square (LIGGGHTS, in process, to 75 us: past the first conversion at 59 us): the zone
    grows as a square in whole spacings, each conversion keeps the momentum to round-off, the far
    field's nodes and the free particles carry the quarter plate's mass rho a b H / 4 exactly, and
    no far-field element left reaches grow_at."""
    p, growth, _ = _grown_square(str(_plate()), dict(PLATE, **{"clock.t_end": 7.5e-5}))
    built, clock, w = growth.built, growth.built.clock, growth.half_width
    assert w > 2.5e-3
    free = clock.tie.free_particles(built.lattice.n).astype(bool)
    mass = built.dyn.m.sum() + clock.dem.scene.mass[free].sum()
    lam = built.lam
    assert mass == pytest.approx(lam.ply["rho"] * 0.25 * p["geometry.span"] * p["geometry.width"] * lam.thickness,
                                 rel=1e-12)
    hashin, hoffman = growth._indices(built.dyn.region.centroid_strain_stress(clock.u_snapshot)[0])
    assert hoffman.max() < p["zone.grow_at"]


@pytest.mark.slow
def test_a_plate_grown_answers_as_its_final_zone_fixed(femdem):
    """Grown from 2.5 mm, the plate's peak deflection within 1 % of the range its final zone gives
    fixed from t = 0 on the same far-field mesh, one spacing narrower, as wide, and one spacing
    wider (grow_at 2: no element grows them). The fixed zones themselves differ: 4.0 / 4.5 / 5.0 mm
    read 1.269 / 1.300 / 1.352 mm (session 33), so a grown run cannot be held closer than that;
    grown to 4.5 mm it read 1.340 mm."""
    code, s, err = femdem("run", str(_plate()), "--dem", "liggghts", *_sets(PLATE))
    assert code == 0, err
    q = s["qoi"]
    assert q["zone_conversions"] >= 1 and q["zone_conversion_momentum_jump"] < 1e-12
    w, d = q["zone_grown_half_width"], 0.5e-3
    peaks = []
    for width in (w - d, w, w + d):
        code, fixed, err = femdem("run", str(_plate()), "--dem", "liggghts", *_sets(dict(PLATE, **{
            "zone.half_width": width, "zone.grow_at": 2.0})))
        assert code == 0, err
        assert fixed["qoi"]["zone_conversions"] == 0
        peaks.append(fixed["qoi"]["peak_deflection"])
    assert 0.99 * min(peaks) <= q["peak_deflection"] <= 1.01 * max(peaks), (q["peak_deflection"], peaks)


@pytest.mark.slow
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(v=st.floats(1.5, 2.5), cells=st.integers(4, 7), grow_at=st.floats(0.3, 0.7))
def test_a_plate_s_zone_grows_from_any_start(femdem, tmp_path, v, cells, grow_at):
    """The plate from a square of 4-7 particle spacings (0.5 mm), struck at 1.5-2.5 m/s, growing
    at a Hoffman index of 0.3-0.7 (three random draws, -m slow): the ledger closes, each
    conversion keeps the momentum to round-off, and the square grows in whole spacings."""
    sets = dict(PLATE, **{"impactors.ball.velocity": v, "zone.half_width": cells * 0.5e-3, "zone.grow_at": grow_at})
    code, s, err = femdem("run", str(_plate()), "--dem", "liggghts", *_sets(sets))
    assert code == 0, err
    q = s["qoi"]
    assert s["checks"]["energy_balance"]["passed"], s["checks"]["energy_balance"]
    assert q["zone_conversion_momentum_jump"] < 1e-12
    w = q["zone_grown_half_width"]
    assert w >= cells * 0.5e-3 and abs(w / 0.5e-3 - round(w / 0.5e-3)) < 1e-6


@pytest.mark.parametrize("name, sets, key", [
    ("clamped_plate", {"zone.shape": "cylinder"}, "zone.shape"),
    ("panel_buckling_coarse", {}, "zone.grow"),
    ("rod_impact_coarse", {"zone.grow_to": 0.063}, "zone.grow_to"),  # past half the radius (60 mm)
    ("rod_impact_coarse", {"zone.grow_to": 0.0445}, "zone.grow_to"),  # not whole spacings (3 mm) from 30 mm
    ("rod_impact_coarse", {"zone.conversion": "release"}, "zone.conversion"),
])
def test_growth_on_other_shapes_is_refused(femdem, name, sets, key):
    case = str(_plate()) if name == "clamped_plate" else name
    code, s, err = femdem("run", case, "--mode=coupled", *_sets(dict({"zone.grow": True}, **sets)))
    assert code == 2 and key in err and ("allowed" in err or "known keys" in err) and s is None


# the rod's 100 m/s with carbon/epoxy strengths in the zone's plies: the far field's Hoffman index
# reaches grow_at (0.5) beyond the 30 mm square within 14 us
DISC = {"zone.grow": True, "zone.ply_failure": True}


def _element_volumes(region) -> float:
    """m^3, the Hex8 mesh's volume by its own map (trilinear: 2-point Gauss is exact), apart
    from the FEM's mass lumping."""
    import skfem
    basis = skfem.Basis(region.mesh, skfem.ElementHex1(), intorder=3)
    return float(skfem.Functional(lambda w: 1.0 + 0.0 * w.x[0]).assemble(basis))


def test_a_disc_s_square_zone_grows_keeping_momentum_and_mass():
    """rod_impact_coarse coupled (LIGGGHTS, in process, to just past the first conversion): the
    square grows in whole spacings over the reserve the O-grid keeps for it (the far field the
    old one less cells), the conversion keeps the momentum to round-off, the far field's nodes
    and the free particles carry rho (V + a^2 H), V the remaining elements' volume by their own
    map and a^2 H the square's, and no far-field element within the zone's limit is left at
    grow_at."""
    p, growth, region0 = _grown_square("rod_impact_coarse", dict(DISC, **{"clock.t_end": 1.6e-5}))
    built, clock, d, w = growth.built, growth.built.clock, growth.built.t, growth.half_width
    assert w > p["zone.half_width"]
    region = built.dyn.region
    kept = region0.n_elements - region.n_elements
    assert kept == int(round((w / d) ** 2 - (p["zone.half_width"] / d) ** 2)) * sum(built.lam.plies) * \
        p["mesh.elements_per_ply"]  # the old mesh less the square's new cells, through the thickness
    free = clock.tie.free_particles(built.lattice.n).astype(bool)
    mass = built.dyn.m.sum() + clock.dem.scene.mass[free].sum()
    H = built.lam.thickness
    assert mass == pytest.approx(built.lam.ply["rho"] * (_element_volumes(region) + w * w * H), rel=1e-12)
    hashin, hoffman = growth._indices(region.centroid_strain_stress(clock.u_snapshot)[0])
    inside = growth._x0 < growth.limit * (1 - 1e-9)  # the reserve's elements left
    assert not inside.any() if w == pytest.approx(growth.limit) else hoffman[inside].max() < p["zone.grow_at"]


# plies at the strong end of the case's ranges and the rod at its slowest: the rod's face grows
# the square from 30 mm at once, the zone's own damage then to the limit; the far field's
# Hoffman index stays low
DISC_STRONG = dict(DISC, **{"materials.table3.Yt": 80e6, "materials.table3.Yc": 250e6, "materials.table3.S12": 110e6,
                            "materials.table3.S23": 90e6, "impactors.rod.velocity": 50.0})


@pytest.mark.slow
def test_a_disc_grown_answers_as_its_final_zone_fixed(femdem):
    """rod_impact_coarse as the case has it (elastic plies, 100 m/s), grown from its 30 mm
    square as the rod's face and the margin ask, against the final square fixed from t = 0 on
    the same far-field mesh (65 s): the plate's peak deflection and the layers' peak separation
    within 1 %, the rod's final velocity within 1 % of its impact speed (measured 0.57 %, 0.09 %,
    0.6 %), momentum to round-off. (With failing plies the cracked plate's answer moves with the
    zone's size itself, docs/limits.md: no grown run can be held to one fixed zone there.)"""
    code, s, err = femdem("run", "rod_impact_coarse", "--mode=coupled", "--set=zone.grow=true")
    assert code == 0, err
    q = s["qoi"]
    assert q["zone_conversions"] >= 1 and q["zone_conversion_momentum_jump"] < 1e-12
    code, fixed, err = femdem("run", "rod_impact_coarse", "--mode=coupled", "--set=zone.grow=true",
                              f"--set=zone.half_width={q['zone_grown_half_width']}")
    assert code == 0, err
    f = fixed["qoi"]
    assert f["zone_conversions"] == 0
    for key in ("peak_plate_deflection", "peak_layer_separation"):
        assert abs(q[key] / f[key] - 1) < 0.01, (key, q[key], f[key])
    assert abs(q["final_rod_velocity"] - f["final_rod_velocity"]) < 0.01 * s["parameters"]["impactors.rod.velocity"]


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["yade", "lammps"])
def test_a_disc_s_square_grows_on_every_engine(femdem, engine):
    """rod_impact_coarse grown from 30 mm on the other engines (to 40 us, the strong plies): the
    same conversions as on LIGGGHTS, momentum to round-off, the plate's deflection at the end
    within 1 % of LIGGGHTS's (the engines integrate alike)."""
    runs = []
    for dem in ("liggghts", engine):
        code, s, err = femdem("run", "rod_impact_coarse", "--mode=coupled", "--dem", dem,
                              *_sets(dict(DISC_STRONG, **{"clock.t_end": 4e-5})))
        assert code == 0, err
        q = s["qoi"]
        assert q["zone_conversions"] >= 1 and q["zone_conversion_momentum_jump"] < 1e-12
        runs.append(q)
    assert runs[1]["zone_conversions"] == runs[0]["zone_conversions"]
    assert runs[1]["zone_grown_half_width"] == pytest.approx(runs[0]["zone_grown_half_width"])
    assert abs(runs[1]["peak_plate_deflection"] / runs[0]["peak_plate_deflection"] - 1) < 0.01


def _disc_ranges():
    """--set lists over every key of rod_impact_coarse's [ranges] at once, the plies whole
    particle spacings (3 mm: 12 or 15 mm)."""
    import tomllib
    ranges = tomllib.loads((SEED_CASES / "rod_impact_coarse.toml").read_text())["ranges"]
    draws = {k: verified(v) for k, v in ranges.items() if k != "laminates.plate.ply_thickness"}
    draws["laminates.plate.ply_thickness"] = st.sampled_from([12e-3, 15e-3])
    return st.fixed_dictionaries(draws).map(lambda v: set_args({**v, "zone.grow": "true", "zone.ply_failure": "true"}))


@pytest.mark.slow
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(dem=st.sampled_from(["liggghts", "lammps", "yade"]), sets=_disc_ranges())
def test_a_disc_grows_anywhere_in_its_ranges(femdem, tmp_path, dem, sets):
    """rod_impact_coarse coupled with failing plies, every key of its [ranges] drawn at once
    (three random draws over the engines, -m slow): it grows, each conversion keeps the
    momentum to round-off and changes the stored energy by less than 1e-2 of the total, the
    zones are whole spacings that only grow, and the ledger's balance closes to 1e-2. OPEN
    (session 33): it fails on YADE. A draw (50 m/s, rod 15 mm, E22 6.3 GPa, Yt 30 MPa) changed
    the stored energy by -1.16e-2 at its first conversion, under the rod at 0.36 us; LIGGGHTS's
    draw 1.4e-4, and 1e-12 on the case's own run."""
    code, s, err = femdem("run", "rod_impact_coarse", "--mode=coupled", "--dem", dem, *sets)
    assert code == 0, err
    q = s["qoi"]
    assert q["zone_conversions"] >= 1 and q["zone_conversion_momentum_jump"] < 1e-12
    assert q["zone_conversion_energy_jump"] < 1e-2 and s["energy"]["balance_error_rel"] < 1e-2
    runs = sorted(tmp_path.glob("run*"), key=lambda d: d.stat().st_mtime)
    with h5py.File(runs[-1] / "history.h5") as h:
        widths = h["history"]["zone.conversion_half_width"][:]
    d = s["parameters"]["zone.particle_size"]
    assert np.all(np.diff(np.concatenate([[s["parameters"]["zone.half_width"]], widths])) > 0)
    assert np.allclose(widths / d, np.round(widths / d), atol=1e-6)


def test_a_disc_resumed_after_a_conversion_finishes_as_the_uninterrupted_one(tmp_path):
    """rod_impact_coarse, LIGGGHTS in process, the checkpoint at four fifths of 20 us (after the
    conversion at 14 us)."""
    _resumed_as_straight(tmp_path, "rod_impact_coarse", dict(DISC, **{"clock.t_end": 2e-5}), "liggghts", 0.8)


RANGES = {"geometry.span": (40e-3, 80e-3), "impactors.cylinder.radius": (3e-3, 8e-3),
          "impactors.cylinder.velocity": (1.0, 12.0), "impactors.cylinder.mass_per_width": (0.3, 1.2)}


def _grows_anywhere(femdem, tmp_path, draw: dict, engine: str, t_end: float):
    """A growing zone over the beam's documented ranges (span, impactor radius, speed, mass),
    the starting zone (3 to 10 spacings) and grow_at: it runs; each conversion keeps the
    momentum to round-off; the zones only grow, in whole spacings; the zone's edge never
    damages."""
    values = {k: draw[k] for k in RANGES}
    d = 2 * 0.15e-3
    sets = dict(values, **{"zone.grow": True, "zone.half_width": draw["columns"] * d, "zone.grow_at": draw["grow_at"],
                           "clock.t_end": t_end})
    code, s, err = femdem("run", "beam_impact_coarse", "--dem", engine, *_sets(sets))
    assert code == 0, (sets, err)
    q = s["qoi"]
    run = sorted(p for p in tmp_path.iterdir() if p.name.startswith("run"))[-1]
    with h5py.File(run / "history.h5") as h:
        g = h["history"]
        jumps_P, widths = g["zone.conversion_momentum_jump"][:], g["zone.conversion_half_width"][:]
    assert np.all(jumps_P < 1e-12), sets
    assert np.all(np.diff(np.concatenate([[sets["zone.half_width"]], widths])) > 0)
    assert np.allclose(widths / d, np.round(widths / d), atol=1e-6)
    assert q["damage_at_zone_edge"] == 0.0, (sets, q)


_DRAW = dict(**{k: st.floats(*v) for k, v in RANGES.items()}, columns=st.integers(3, 10), grow_at=st.floats(0.1, 0.5))


@settings(max_examples=1, deadline=None, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(draw=st.fixed_dictionaries(_DRAW))
def test_a_zone_grows_anywhere_in_the_beam_s_ranges(femdem, tmp_path, draw):
    """One draw (the suite's), 20 us of the impact on LIGGGHTS."""
    _grows_anywhere(femdem, tmp_path, draw, "liggghts", 2e-5)


@pytest.mark.slow
@settings(max_examples=6, deadline=None, derandomize=False,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(draw=st.fixed_dictionaries(_DRAW), engine=st.sampled_from(["liggghts", "lammps", "yade"]))
def test_a_zone_grows_anywhere_in_the_beam_s_ranges_on_every_engine(femdem, tmp_path, draw, engine):
    """Six random draws over the three engines, the whole impact (0.6 ms)."""
    _grows_anywhere(femdem, tmp_path, draw, engine, 0.0)


@pytest.mark.slow
def test_a_zone_grown_over_a_delaminating_far_field_carries_its_softening(femdem, tmp_path):
    """The full seed beam from a 0.6 mm zone (about 50 s each run): the zone grows over far-field
    cohesive pairs that are softening; each pair's softening state carries onto the particle
    bonds (HashinCohesiveLaw.softening), so the conversions keep the stored energy (below 2e-3
    of the total, 1.2e-3 measured; 3.7e-2 when the damage value was carried and the delamination
    was lost; below 1e-3 was asserted until session 29, when the first sample of a grown model
    stopped counting the symmetry plane's held components, which had offset part of it), and
    the beam delaminates as the final zone fixed from t = 0 on the same far-field mesh does
    (growth off: grow_at above any index, no margin): the total debonded length within 5 % (the
    two 0/90 interfaces are a near tie, which one runs is not asserted) and the peak deflection
    within 2 %."""
    grown = ("--set=zone.grow=true", "--set=zone.half_width=0.6e-3")
    code, s, err = femdem("run", "beam_impact", "--dem", "liggghts", *grown)
    assert code == 0, err
    q = s["qoi"]
    assert q["zone_conversions"] >= 2 and q["zone_conversion_energy_jump"] < 2e-3
    assert not [w for w in s["warnings"] if "changed the stored energy" in w]
    w = q["zone_grown_half_width"]
    code, f, err = femdem("run", "beam_impact", "--dem", "liggghts", "--set=zone.grow=true", f"--set=zone.half_width={w}",
                          "--set=zone.grow_at=2", "--set=zone.margin=1e-9")
    assert code == 0, err
    assert f["qoi"]["zone_conversions"] == 0
    debonded = lambda q: q["delamination_length_0"] + q["delamination_length_1"]
    assert debonded(f["qoi"]) > 0.25 * 50e-3  # the fixed zone's beam delaminates (over more than a quarter of its span)
    assert debonded(q) == pytest.approx(debonded(f["qoi"]), rel=0.05)
    assert q["peak_centre_displacement"] == pytest.approx(f["qoi"]["peak_centre_displacement"], rel=0.02)


@pytest.mark.parametrize("name, sets, dem, at", [
    # YADE's own checkpoint file, and beside it the force container (the next move's forces:
    # recomputed at a restore, they lacked the hook's laws and impactor, 4 % off in momentum)
    ("beam_impact_coarse", dict(GROW, **{"clock.t_end": 9e-6}), "yade", 2 / 3),
    pytest.param("beam_impact_3d_coarse", dict(GROW_3D, **{"clock.t_end": 1e-5}), "liggghts", 0.8,
                 marks=pytest.mark.slow),
    pytest.param("clamped_plate", dict(PLATE, **{"clock.t_end": 7.5e-5}), "liggghts", 0.8, marks=pytest.mark.slow)])
def test_a_run_resumed_after_a_conversion_finishes_as_the_uninterrupted_one_anywhere(tmp_path, name, sets, dem, at):
    """The same on YADE (in the default suite), on the 3D strip and on the plate's square zone."""
    _resumed_as_straight(tmp_path, str(_plate()) if name == "clamped_plate" else name, sets, dem, at)


@pytest.mark.parametrize("name", ["cfrp_beam_impact", "cfrp_beam_impact_coarse"])
@given(span_rows=st.integers(-40, 0))
@settings(max_examples=8, deadline=None)
def test_a_bonded_beam_s_zone_can_be_built_at_its_growth_limit(name, span_rows):
    """The last whole spacing four short of the support (grow_limit, a grown zone's farthest
    reach) is a zone the beam accepts, for the case's span and shorter ones (fractions of a row apart,
    within its ranges): the full CFRP beam's limit, d floor(s / d - 4), reads an ulp past s - 4 d, and its
    zone, grown there mid-run, was refused (the run ended with an error at 345.44 mm)."""
    from coupling.study import bonded
    case = load_case(name)
    p = case.parameters
    d = p["zone.particle_size"]
    span = p["geometry.span"] + 0.37 * d * span_rows
    case = load_case(name, {"geometry.span": span, "geometry.length": max(p["geometry.length"], span)})
    p = case.parameters
    limit = bonded.grow_limit(p, bonded.bonded_of(case.scene, p))
    sim, built = case.scene.assemble(dict(p, **{"zone.half_width": limit, "zone.grow": False}), "coupled", "liggghts")
    sim.close()
    assert built.lattice.x[:, 0].max() == pytest.approx(limit, rel=1e-9)
