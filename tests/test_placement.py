"""The DEM zone placed from an all-FEM estimate (zone.placement = "auto", issue #25 part 1):
the growth rule against a brute-force fixed point, the decision's refusals and warnings on
made-up estimates, and a placed zone that gives the all-DEM beam's answer."""
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st

from coupling.params import CaseError
from coupling.study.placement import Estimate, decide, grown_reach

from conftest import assert_checks

intervals = st.lists(st.tuples(st.floats(0.0, 50.0), st.floats(0.01, 5.0)), max_size=30)


@settings(max_examples=200, deadline=None)
@given(intervals, st.floats(0.0, 10.0), st.floats(0.0, 3.0))
def test_the_zone_grows_over_every_flagged_element_it_reaches(elements, start, margin):
    """The reach is the least r >= start that every element either lies inside (x1 <= r) or
    begins beyond r + margin: the fixed point of r = max(start, x1 of the elements beginning
    within margin of r), iterated from start."""
    x0 = np.array([a for a, _ in elements])
    x1 = x0 + np.array([b for _, b in elements])
    r = grown_reach(x0, x1, start, margin)
    assert r >= start
    assert np.all((x1 <= r) | (x0 > r + margin))
    fixed = start
    while True:
        near = x0 <= fixed + margin
        nxt = max(start, x1[near].max(initial=start))
        if nxt == fixed:
            break
        fixed = nxt
    assert r == fixed


def _estimate(profile, length=1e-3, contact=0.0):
    """Elements of ``length`` (m) side by side from x = 0 with the Hoffman peaks ``profile``."""
    x0 = length * np.arange(len(profile))
    return Estimate(x0, x0 + length, {"Hoffman": np.asarray(profile, float)}, contact, 0.0)


def test_the_zone_holds_the_flagged_elements_and_its_margin_in_whole_particles():
    d, L = 0.3e-3, 25e-3
    placed = decide(_estimate([0.9, 0.8, 0.6, 0.4, 0.2] + [0.1] * 20), d, L, grow_at=0.5, margin=1.2e-3)
    assert placed.reach == pytest.approx(3e-3)
    w = placed.half_width
    assert w >= 3e-3 + 1.2e-3 and w - (3e-3 + 1.2e-3) < d  # the margin, rounded up
    assert abs(w / d - round(w / d)) < 1e-9
    assert not placed.warnings


def test_an_impact_that_flags_nothing_keeps_the_contact_patch_and_a_punch_on_particles():
    d = 0.3e-3
    assert decide(_estimate([0.1] * 25, contact=0.2e-3), d, 25e-3, 0.5, 1.2e-3).half_width == \
        pytest.approx(np.ceil((0.2e-3 + 1.2e-3) / d - 1e-9) * d)
    punch = 2e-3
    w = decide(_estimate([0.1] * 25), d, 25e-3, 0.5, 1e-4, punch=punch).half_width
    assert w >= punch + 2 * d


def test_a_flagged_region_apart_from_the_impact_is_left_to_the_far_field_with_a_warning():
    profile = [0.9, 0.7] + [0.1] * 15 + [1.2, 1.1] + [0.1] * 6  # a clamp's bending near x = 18 mm
    placed = decide(_estimate(profile), 0.3e-3, 25e-3, 0.5, 2.4e-3)
    assert placed.half_width < 5e-3
    assert len(placed.warnings) == 1 and "Hoffman index at 1.20 at x = 17.5 mm" in placed.warnings[0]
    assert placed.peak == pytest.approx(1.2)


def test_a_zone_the_box_cannot_hold_is_refused_with_what_would_fit():
    with pytest.raises(CaseError, match=r"zone.placement = 'auto'.*out to x = 21 mm.*allowed at most 0.8 x half"):
        decide(_estimate([0.9] * 21 + [0.1] * 4), 0.3e-3, 25e-3, 0.5, 1.2e-3)
    # nothing flagged, no criterion (elastic plies, cohesive far field): the margin is to blame
    nothing = Estimate(np.arange(25) * 1e-3, np.arange(1, 26) * 1e-3, {}, 1e-3, 0.0)
    with pytest.raises(CaseError, match=r"contact patch \(1 mm\) and the margin \(20 mm\)"):
        decide(nothing, 0.3e-3, 25e-3, 0.5, 20e-3)


def test_a_tied_far_field_that_delaminates_everywhere_is_refused_before_anything_is_written(femdem, tmp_path):
    """The seed beam with tied far-field plies: its interlaminar index reaches grow_at along the
    whole span (issue #24's finding), so no zone about the impact holds it; exit 2, no run
    directory, and the line names the setting that lets the far field delaminate."""
    code, s, err = femdem("run", "beam_impact_coarse", "--set=laminates.beam.far_field_interfaces=tied",
                          "--set=zone.placement=auto", "--set=clock.t_end=1e-4")
    assert code == 2 and s is None
    assert "interlaminar index" in err and "far_field_interfaces = 'cohesive'" in err
    assert not (tmp_path / "run0").exists()


def test_placement_is_refused_where_a_zone_is_not_a_box_about_the_impact(femdem):
    code, _, err = femdem("run", "rod_impact_coarse", "--set=zone.placement=auto")
    assert code == 2 and "zone.placement" in err


BEAM = dict(span=st.floats(20e-3, 40e-3), radius=st.floats(3e-3, 8e-3), velocity=st.floats(2.0, 12.0),
            mass=st.floats(0.3, 1.2))


def placed_against_all_dem(femdem, dem, span, radius, velocity, mass):
    """The coarse seed beam (half span ``span``) coupled with its zone placed, and all-DEM, on
    ``dem``: (coupled summary, all-DEM summary)."""
    # to about twice the peak's time: 0.17 ms at the defaults (half span 25 mm, 0.617 kg/m),
    # scaled as the spring-mass period sqrt(M / k), k ~ 1 / span^3
    t_end = min(0.6e-3, 0.35e-3 * np.sqrt(mass / 0.617) * (span / 25e-3) ** 1.5)
    sets = [f"--set=geometry.span={2 * span}", f"--set=impactors.cylinder.radius={radius}",
            f"--set=impactors.cylinder.velocity={velocity}", f"--set=impactors.cylinder.mass_per_width={mass}",
            f"--set=clock.t_end={t_end}"]
    runs = []
    for mode, extra in (("coupled", ["--set=zone.placement=auto"]), ("dem", [])):
        code, s, err = femdem("run", "beam_impact_coarse", "--mode", mode, "--dem", dem, *sets, *extra)
        assert code == 0, err
        assert_checks(s)
        runs.append(s["qoi"])
    return runs


def _assert_placed_zone_gives_all_dem(coupled, dem, H=2.4e-3):
    margin = H  # the laminate's thickness, above 4 particle sizes (1.2 mm)
    assert coupled["zone_estimate_reach"] + margin <= coupled["zone_half_width"] + 1e-12
    # the contact chatters (the cylinder leaves and strikes again): its largest spike differs by
    # up to 20 % between models whose impulse agrees to 1.5 % (a 12 mm hand-drawn zone: 12 %)
    for qoi, tol in (("peak_centre_displacement", 0.06), ("contact_force_impulse", 0.05), ("peak_contact_force", 0.25)):
        assert abs(coupled[qoi] / dem[qoi] - 1) < tol, (qoi, coupled[qoi], dem[qoi])
    assert coupled["damage_at_zone_edge"] == 0.0  # no damage the far field cannot carry reached the edge
    debonded = [max((k for k in q if k.startswith("delamination_length_")), key=q.get) for q in (coupled, dem)]
    if dem[debonded[1]] > 0:  # the interface that debonds is the all-DEM one's
        assert debonded[0] == debonded[1], (coupled, dem)


# -m slow: the seed's impact (25 s; the default suite's budget: its decisions are tested above on
# made-up estimates), and the ranges below
@pytest.mark.slow
@settings(max_examples=1, deadline=None, phases=[Phase.explicit],
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(**BEAM)
@example(span=25e-3, radius=5e-3, velocity=10.0, mass=0.617)  # the seed's impact: an interface debonds
def test_a_placed_zone_gives_the_all_dem_beam_at_the_seed_impact(femdem, span, radius, velocity, mass):
    """The coarse seed beam, coupled with the zone placed from its all-FEM estimate: peak
    deflection within 6 % and the contact's impulse within 5 % of the all-DEM beam's (the hand-drawn 12 mm zone: 4.5 % and 0.4 % at the defaults), no damage the
    far field cannot carry at the zone's edge, and the interface that debonds is the all-DEM
    one's."""
    _assert_placed_zone_gives_all_dem(*placed_against_all_dem(femdem, "liggghts", span, radius, velocity, mass))


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(**BEAM, dem=st.sampled_from(["yade", "liggghts", "lammps"]))
@example(span=25e-3, radius=5e-3, velocity=12.0, mass=1.0, dem="liggghts")  # the plies crack: the zone grows
@example(span=20e-3, radius=3e-3, velocity=2.0, mass=0.3, dem="liggghts")  # the mildest corner
def test_a_placed_zone_gives_the_all_dem_beam_on_every_engine(femdem, span, radius, velocity, mass, dem):
    _assert_placed_zone_gives_all_dem(*placed_against_all_dem(femdem, dem, span, radius, velocity, mass))


@pytest.mark.slow
def test_a_placed_zone_gives_the_all_dem_3d_strip(femdem):
    """The 3D seed strip (beam_impact_3d_coarse: a quarter, Hex8 far field with cohesive plies)
    coupled on LIGGGHTS with its zone placed from its all-FEM estimate, against all-DEM: the same
    bounds as the 2D beam (deflection 6 %, impulse 5 %, force 25 %), no damage the far field
    cannot carry at the zone's edge. Which 0/90 interface debonds is not asserted: on this strip
    the two are a near tie that the far field's mesh decides (docs/status.md, #24 session 29)."""
    runs = []
    for mode, extra in (("coupled", ["--set=zone.placement=auto"]), ("dem", [])):
        code, s, err = femdem("run", "beam_impact_3d_coarse", "--mode", mode, "--dem", "liggghts", *extra)
        assert code == 0, err
        assert_checks(s)
        runs.append(s["qoi"])
    H = 2.4e-3  # the laminate's thickness: the margin (above 4 particle sizes)
    coupled, dem = runs
    assert coupled["zone_estimate_reach"] + H <= coupled["zone_half_width"] + 1e-12
    for qoi, tol in (("peak_centre_displacement", 0.06), ("contact_force_impulse", 0.05), ("peak_contact_force", 0.25)):
        assert abs(coupled[qoi] / dem[qoi] - 1) < tol, (qoi, coupled[qoi], dem[qoi])
    assert coupled["damage_at_zone_edge"] == 0.0
