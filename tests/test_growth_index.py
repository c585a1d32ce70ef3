"""The growth check's compiled criterion (study/fields.ElementIndex) is the seed's criteria
(physics/failure.py on FemIndices' ply stresses) at every element, on any mesh and laminate."""
import numpy as np
import skfem
from hypothesis import given, settings, strategies as st

from coupling.study.fields import BondedIndices, ElementIndex, FemIndices
from fem_region import materials
from fem_region.elements import ELEMENTS
from fem_region.region import FemRegion

MESHES = {"quad4": skfem.MeshQuad, "tri3": skfem.MeshTri, "hex8": skfem.MeshHex, "tet4": skfem.MeshTet}


def _laminate(angles, elastic: bool):
    from coupling.study.assemble import Laminate
    ply = dict(E11=140e9, E22=9e9, G12=5e9, G23=3.2e9, nu12=0.3, nu23=0.4, rho=1500.0, Xt=1.6e9, Xc=1.2e9,
               Yt=50e6, Yc=200e6, S12=80e6, S23=60e6, Gf_fibre=4e4, Gf_matrix=300.0)
    return Laminate(list(angles), [1] * len(angles), 1e-3 / len(angles), ply,
                    dict(Z0=40e6, R0=25e6, GIc=200.0, GIIc=600.0, friction=0.3), elastic)


@given(name=st.sampled_from(sorted(MESHES)), angles=st.lists(st.sampled_from([0.0, 90.0, 45.0, -30.0]),
                                                            min_size=1, max_size=4),
       which=st.sampled_from([(True, True), (True, False), (False, True)]), seed=st.integers(0, 2**31),
       strain=st.floats(1e-4, 3e-2))
@settings(max_examples=40, deadline=None)
def test_the_compiled_index_is_the_seed_criteria_at_every_element(name, angles, which, seed, strain):
    e = ELEMENTS[name]
    m = MESHES[name].init_tensor(*[np.linspace(0, 1e-3, 4)] * e.dim)
    lam = _laminate(angles if e.dim == 3 else [a for a in angles if a in (0.0, 90.0)] or [0.0], elastic=False)
    D = materials.reduce(lam.stiffness(0.0, e.dim), e.dim, "plane_strain")
    region = FemRegion(m, e, D, 1500.0, 1.0)
    fi = FemIndices(region, lam, e.dim)
    hoff_on, hashin_on = which
    index = ElementIndex(region, fi.ply_stress, hoff_on, hashin_on, fi.k, fi.Z0, fi.R0)
    u = strain * 1e-3 * np.random.default_rng(seed).standard_normal(region.X.shape)  # a rough field
    hashin, hoffman = fi(region.centroid_strain_stress(u)[0])
    expect = np.maximum(hoffman if hoff_on else 0.0, hashin if hashin_on else 0.0)
    got = index(u)
    assert got.shape == (region.n_elements,)
    np.testing.assert_allclose(got, expect, rtol=1e-10, atol=1e-12 * np.abs(expect).max())


def test_per_element_switches_and_a_nan():
    """Each criterion only where its switch is on, element by element (a bonded beam's Hashin on
    its bottom row; a mask drawn at random here, for both criteria); asked at some elements, the
    index there and the others left as they were; a nan displacement gives a
    nan index on the elements it touches, as numpy's maximum does, and nothing elsewhere."""
    e = ELEMENTS["quad4"]
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 2e-3, 6), np.linspace(0, 1e-3, 4))
    lam = _laminate([0.0, 90.0], elastic=False)
    region = FemRegion(m, e, lam.D(0.0), 1500.0, 1.0)
    fi = FemIndices(region, lam, 2)
    rng = np.random.default_rng(7)
    hoff_on, hashin_on = rng.random(region.n_elements) < 0.5, rng.random(region.n_elements) < 0.5
    u = 2e-5 * rng.standard_normal(region.X.shape)
    hashin, hoffman = fi(region.centroid_strain_stress(u)[0])
    index = ElementIndex(region, fi.ply_stress, hoff_on, hashin_on, fi.k, fi.Z0, fi.R0)
    expect = np.maximum(np.where(hoff_on, hoffman, 0.0), np.where(hashin_on, hashin, 0.0))
    np.testing.assert_allclose(index(u), expect, rtol=1e-10, atol=1e-300)
    assert np.any(hoff_on & (hoffman > hashin) & (index(u) > 0)) and np.any(~hoff_on & hashin_on)
    some = rng.permutation(region.n_elements)[: region.n_elements // 3]  # (a check's elements near the edge)
    index.out[:] = -7.0
    got = index(u, some)
    np.testing.assert_allclose(got[some], expect[some], rtol=1e-10, atol=1e-300)
    assert np.all(np.delete(got, some) == -7.0)  # the others as they were
    u[5, 1] = np.nan
    touched = np.any(region.mesh.t.T == 5, axis=1) & (hoff_on | hashin_on)
    got = index(u)
    assert np.all(np.isnan(got[touched])) and not np.any(np.isnan(got[~touched]))


def test_per_element_switches_and_elastic_plies():
    """Hashin only where hashin_on (a bonded beam's bottom row); infinite strengths (elastic
    plies) give a Hoffman index of 0."""
    e = ELEMENTS["quad4"]
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 2e-3, 5), np.linspace(0, 1e-3, 3))
    lam = _laminate([0.0, 90.0], elastic=True)
    region = FemRegion(m, e, lam.D(0.0), 1500.0, 1.0)
    fi = FemIndices(region, lam, 2)
    rows = np.random.default_rng(3).random(region.n_elements) < 0.5
    u = 1e-5 * np.random.default_rng(4).standard_normal(region.X.shape)
    hashin, hoffman = fi(region.centroid_strain_stress(u)[0])
    assert np.all(hoffman == 0.0)
    got = ElementIndex(region, fi.ply_stress, True, rows, fi.k, fi.Z0, fi.R0)(u)
    np.testing.assert_allclose(got, np.where(rows, hashin, 0.0), rtol=1e-10, atol=1e-300)
    assert np.all(got[~rows] == 0.0) and np.any(got[rows] > 0.0)


def test_the_window_s_crack_plane_index_is_hashin_s_on_the_band():
    """A specimen's window (scenes/window_growth.py): Hashin's index of the centroid s_yy and
    s_xy on the band's elements, 0 elsewhere."""
    from coupling.scenes.window_growth import WindowGrowth
    e = ELEMENTS["quad4"]
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 4e-3, 9), np.linspace(0, 2e-3, 5))
    region = FemRegion(m, e, materials.reduce(materials.isotropic(10e9, 0.3), 2, "plane_strain"), 1500.0, 1.0)
    band = np.arange(region.n_elements) % 3 == 0
    Z0, R0 = 30e6, 60e6
    u = 1e-6 * np.random.default_rng(5).standard_normal(region.X.shape)
    s = region.centroid_strain_stress(u)[1]
    expect = np.where(band, (np.maximum(s[:, 1], 0.0) / Z0) ** 2 + (s[:, 2] / R0) ** 2, 0.0)
    got = ElementIndex(region, WindowGrowth._plane_stress(region), False, band, None, Z0, R0)(u)
    np.testing.assert_allclose(got, expect, rtol=1e-10, atol=1e-300)
    assert np.all(got[band] > 0)


@given(seed=st.integers(0, 2**31), n=st.integers(0, 60), at=st.floats(0.05, 2.0))
@settings(max_examples=40, deadline=None)
def test_the_compiled_reaches_are_their_numpy_forms(seed, n, at):
    """The check's other reductions (physics/kernels.py) against the numpy forms they replaced
    (coupling/study/growth.py and scenes/window_growth.py until session 38): the farthest
    damaged bond, the farthest particle inside a sphere or a cylinder, the farthest crack-plane
    bond in or about to join the cohesive zone."""
    from physics.kernels import cohesive_reach, damaged_reach, flagged_reach, touched_reach
    rng = np.random.default_rng(seed)
    reach, damage = rng.random(n), np.where(rng.random(n) < 0.3, rng.random(n), 0.0)
    assert damaged_reach(reach, damage) == (reach[damage > 0].max() if np.any(damage > 0) else -1.0)
    x, centre, radius = rng.normal(size=(n, 3)), rng.normal(size=3), 1.2
    for axis in (None, rng.normal(size=3)):
        r = x - centre
        if axis is not None:
            r = r - np.outer(r @ axis, axis) / (axis @ axis)
        touching = np.linalg.norm(r, axis=1) < radius
        for cols in (1, 2):
            expect = float(np.abs(x[touching, :cols]).max()) if touching.any() else -1.0
            assert touched_reach(x, centre, np.zeros(3) if axis is None else axis, radius, cols) == expect
    t, normal = 30e6 * rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    damage = np.where(rng.random(n) < 0.3, rng.choice([0.5, 1.0], n), 0.0)
    Z0, R0, xb = 30e6, 40e6, rng.random(n)
    tn = np.einsum("bi,bi->b", t, normal)
    ts = np.linalg.norm(t - tn[:, None] * normal, axis=1)
    index = (np.maximum(tn, 0.0) / Z0) ** 2 + (ts / R0) ** 2
    near = np.abs(index - at) < 1e-12 * at  # (the two forms round apart only on the threshold)
    chosen = ((index >= at) | (damage > 0)) & (damage < 1.0) & ~near
    got = cohesive_reach(t, normal, damage, xb, Z0, R0, at)
    if not near.any():
        assert got == (xb[chosen].max() if chosen.any() else -1.0)
    if n >= 2:  # a nan damage or traction flags nothing, as numpy's comparisons did
        damage[0], t[1] = np.nan, np.nan
        assert cohesive_reach(t, normal, damage, xb, Z0, R0, at) <= got
        index = np.full(n, np.nan)
        assert flagged_reach(index, np.arange(n), xb, xb + 1.0, at, 0.0, 10.0) == 0.0


@given(seed=st.integers(0, 2**31), n=st.integers(0, 50), at=st.floats(0.1, 1.0), start=st.floats(0.0, 0.5),
       margin=st.floats(0.0, 0.3))
@settings(max_examples=60, deadline=None)
def test_the_compiled_flagged_reach_is_placement_s(seed, n, at, start, margin):
    """Growth's reach over the elements its index flags (physics/kernels.flagged_reach, the
    elements sorted once) against placement.grown_reach over the flagged ones alone (the same
    rule, held to its fixed point in tests/test_placement.py), on elements that overlap, touch
    and leave gaps (x0 on a coarse grid, so that ties occur)."""
    from coupling.study.placement import grown_reach
    from physics.kernels import flagged_reach
    rng = np.random.default_rng(seed)
    x0 = np.round(rng.random(n) * 10) / 10
    x1 = x0 + rng.random(n) * 0.3
    index = rng.random(n) * 1.2
    flagged = index >= at
    expect = grown_reach(x0[flagged], x1[flagged], start, margin)
    assert flagged_reach(index, np.argsort(x0, kind="stable"), x0, x1, at, start, margin) == expect


def test_the_left_out_damage_warning_says_where_only_when_it_knows():
    """probes.left_out: one line per criterion whose peak reached 1, with the first sample's time
    at 1 and the peak's place; no place when the history does not hold it (a peak taken before a
    resume from a checkpoint written without the place series), none below 1."""
    from coupling.study.probes import left_out
    h = {"time": np.array([0.0, 1e-5, 2e-5, 3e-5]), "ff_hoffman": np.array([0.2, 0.9, 1.3, 1.1]),
         "ff_interlaminar": np.array([0.1, 0.2, 0.3, 0.2])}
    qoi = {"peak_ff_hoffman": 1.3, "x_of_peak_ff_hoffman": 0.0222, "peak_ff_interlaminar": 0.3,
           "x_of_peak_ff_interlaminar": 0.001}
    lines = left_out("ff", h, qoi)
    assert len(lines) == 1 and "Hoffman" in lines[0] and "t = 2e-05 s" in lines[0] and "1.30 at most" in lines[0]
    assert "x = 22.2 mm" in lines[0]
    qoi["x_of_peak_ff_hoffman"] = np.nan
    (line,) = left_out("ff", h, qoi)
    assert "x =" not in line and "nan" not in line
    assert left_out("ff", h, {"peak_ff_hoffman": 0.99}) == []


@given(case=st.sampled_from(["cfrp_beam_impact_coarse", "cfrp_beam_impact_3d_coarse"]), seed=st.integers(0, 2**31),
       scale=st.floats(1e-7, 1e-4))
@settings(max_examples=6, deadline=None)
def test_a_bonded_beam_s_compiled_index_is_its_criteria(case, seed, scale):
    """A bonded beam's growth check (study/growth.py on fields.BondedIndices): the compiled
    criterion is the body's Hoffman index and the adhesive's Hashin index on the bottom row,
    as BondedIndices gives them in numpy, at every element of the grown far field's mesh (2D
    plane stress, 3D); a rough field exercises every strain component."""
    from coupling.case import load_case
    c = load_case(case, {"zone.grow": True})
    sim, built = c.scene.assemble(c.parameters, "coupled", "liggghts")
    try:
        region = built.dyn.region
        fi = BondedIndices(region, built.bonded, built.dim)
        u = scale * np.random.default_rng(seed).standard_normal(region.X.shape)
        hashin, hoffman = fi(region.centroid_strain_stress(u)[0])
        got = ElementIndex(region, fi.ply_stress, True, fi.bottom, fi.k, fi.Z0, fi.R0)(u)
        np.testing.assert_allclose(got, np.maximum(hashin, hoffman), rtol=1e-10, atol=1e-300)
        assert np.any(fi.bottom) and not np.all(fi.bottom) and np.any(got[fi.bottom] > 0)
    finally:
        sim.close()


@given(seed=st.integers(0, 2**31), strain=st.floats(1e-4, 3e-2), tied=st.booleans())
@settings(max_examples=20, deadline=None)
def test_the_far_field_probe_is_the_largest_seed_index_and_where(seed, strain, tied):
    """The far_field_failure probe's series (the compiled pass, each criterion alone) are the
    largest of the seed criteria over the elements (numpy, FemIndices) and that element's
    centroid x, on a rough field; Hashin's only where the far-field plies are tied."""
    from types import SimpleNamespace
    from coupling.study.probes import _far_field_series
    e = ELEMENTS["quad4"]
    m = skfem.MeshQuad.init_tensor(np.linspace(0, 4e-3, 9), np.linspace(0, 1e-3, 5))
    lam = _laminate([0.0, 90.0, 90.0, 0.0], elastic=False)
    region = FemRegion(m, e, lam.D(0.0), 1500.0, 1.0)
    u = strain * 1e-3 * np.random.default_rng(seed).standard_normal(region.X.shape)
    state = SimpleNamespace(u=np.zeros_like(u), t=0.0)
    built = SimpleNamespace(dyn=SimpleNamespace(region=region, state=state), lam=lam, dim=2,
                            node_bonds=None if tied else object())
    series = _far_field_series(built, "ff", {})
    assert sorted(series) == sorted(["ff_hoffman", "ff_hoffman_x"] + (["ff_interlaminar", "ff_interlaminar_x"]
                                                                        if tied else []))
    assert series["ff_hoffman"]() == 0.0  # at rest
    state.u[:], state.t = u, 1e-6
    x = region.X[region.mesh.t.T][:, :, 0].mean(axis=1)
    for name, index in zip(("interlaminar", "hoffman"), FemIndices(region, lam, 2)(region.centroid_strain_stress(u)[0])):
        if f"ff_{name}" in series:
            np.testing.assert_allclose(series[f"ff_{name}"](), index.max(), rtol=1e-10)
            assert series[f"ff_{name}_x"]() == x[np.argmax(index)]
