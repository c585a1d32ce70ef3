"""A crack front runs from the FEM into the DEM window (#24 part 2, the direction the seed beams
do not show: their damage starts in the particles and runs out into the cohesive far field).

A specimen whose window starts ahead of its initial crack (``dem.window_start`` > a0) leaves the
crack's first stretch to the FEM band, cut along the crack plane and joined node to node by the
same interface law as the all-FEM specimen's (coupling/scenes/delamination.py). The crack
starts in the FEM and runs on into the particles. Checked:
- the crack plane is held once along its length, by the FEM's pairs up to half a spacing past
  the window's first column and by the particles' beyond (their areas sum to the plane's);
- the specimens' own closed-form checks hold with the crack crossing, the crack runs through
  the window's first columns, and the load while its cohesive zone crosses the window's edge
  is the all-FEM specimen's (no barrier there), over draws of the ply, the arm, the crack and
  where the window starts (-m slow); a window that grows ahead of the crack as well answers as
  the one fixed from t = 0 over the same span;
- a run killed after a checkpoint resumes to the uninterrupted result, bit for bit (-m slow);
- the refusals.
"""
import json
from pathlib import Path

import h5py
import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, assume, event, given, settings
from hypothesis import strategies as st

from conftest import assert_checks
from coupling.case import load_case
from coupling.cli import main
from coupling.params import CaseError, parse_set
from coupling.scenes import dcb, enf, mixed_mode
from coupling.scenes import delamination as dl
from coupling.scenes import window_growth
from coupling.simulation import run_clock
from test_delamination_ranges import MATERIAL, OUTSIDE, THICK, dcb_sets

CASES = {"dcb_coarse": dcb, "enf_coarse": enf, "mixed_mode_coarse": mixed_mode}


def _window(case: str, p: dict) -> tuple[float, float]:
    """(a0, x_b) m: the initial crack and the end of the case's window placed by its closed form."""
    if case == "dcb_coarse":
        (_, x_b), _ = dcb.domain(p)
    else:
        x_b = enf.window_end_placed(p, CASES[case].closed_form(p), p["zone.particle_size"])
    return p["geometry.crack_length"], x_b


@settings(max_examples=30, deadline=None, derandomize=True)
@given(case=st.sampled_from(sorted(CASES)), where=st.floats(0.0, 1.0), r=st.floats(0.2e-3, 0.25e-3),
       h=st.floats(2.5e-3, 4e-3))
def test_the_crack_plane_is_held_once_from_the_fem_into_the_window(case, where, r, h):
    """Anywhere the window starts between a0 and 4 spacings before its end: the FEM's node pairs
    stand for the plane from x = 0 to half a spacing past the window's first column, at most a
    spacing apart from a0 on (the strengths are resolved on it); the particles' pairs for the
    rest of the window, from its first free column; together their areas are the plane's length
    times the slice's thickness, to round-off. The window's first column's pair stands for
    nothing (its particles move with the band's elements that hold them)."""
    p = load_case(case, {"zone.particle_size": 2 * r, "geometry.arm_thickness": h}).parameters
    try:
        a0, x_b = _window(case, p)
    except CaseError:  # a specimen outside its domain (a crack shorter than 8 h)
        assume(False)
    d = p["zone.particle_size"]
    x_a = a0 + d / 10 + where * (x_b - 4 * d - a0 - d / 10)
    L = p.get("geometry.half_span")
    spec = dl.build_specimen(p, a0, x_a, x_b, omega_arm=1.0, stations=(L, 2 * L) if L else ())  # (the scenes')
    X, t = spec.region.X, spec.t
    x_fem = X[spec.pairs[:, 0], 0]
    assert np.allclose(X[spec.pairs[:, 0]], X[spec.pairs[:, 1]], rtol=0, atol=1e-12)  # coincident
    assert x_fem.min() == pytest.approx(0.0, abs=1e-12) and x_fem.max() == pytest.approx(x_a + d / 2, rel=1e-12)
    assert np.all(np.diff(x_fem[x_fem >= a0 - 1e-12]) <= d * (1 + 1e-9))
    b = spec.bonds
    x_dem = b.X[b.pairs[:, 0], 0]
    assert b.area[0] == 0.0 and x_dem[0] == pytest.approx(x_a, rel=1e-12)
    plane = x_dem[-1] * t  # from x = 0 to the window's last column
    assert spec.pair_area.sum() + b.area.sum() == pytest.approx(plane, rel=1e-12)
    # the FEM's pairs end where the first free column's share begins
    assert spec.pair_area.sum() == pytest.approx((x_a + d / 2) * t, rel=1e-12)


def test_a_window_from_the_crack_tip_keeps_the_fem_band_open_behind_it():
    """The default window (dem.window_start = 0) is the case's: no FEM pairs (the band is open
    behind the window, as before this option), every particle pair of the plane counted."""
    p = load_case("dcb_coarse").parameters
    (x_a, x_b), _ = dcb.domain(p)
    assert window_growth.window_start(p, x_a, x_b) == x_a < p["geometry.crack_length"]
    spec = dl.build_specimen(p, p["geometry.crack_length"], x_a, x_b, omega_arm=1.0)
    assert spec.pairs is None and np.all(spec.bonds.area > 0)


def _run(tmp: Path, name: str, case: str, *sets: str) -> tuple[dict, dict]:
    """(summary, history) of ``femdem run case sets`` in tmp / name."""
    out = tmp / name
    code = main(["run", case, *sets, "--out", str(out), "--quiet"])
    assert (out / "summary.json").exists(), f"exit {code}: nothing written"
    s = json.loads((out / "summary.json").read_text())
    assert code == 0, s.get("message")
    with h5py.File(out / "history.h5") as f:
        return s, {k: v[()] for k, v in f["history"].items()}


def _crossing(p: dict, h: dict, x_a: float, zone: float) -> float:
    """Mean relative error of the DCB's load against corrected beam theory's propagation branch
    P(delta) while the crack tip runs from ``zone`` before x_a to x_a (m): the cohesive zone's
    front crossing into the window."""
    cf = dcb.closed_form(p)
    tip = np.asarray(h["crack_tip"])
    on = np.isfinite(tip) & (tip > x_a - zone) & (tip <= x_a)
    assert on.sum() > 10, "the crack must be sampled crossing"
    return float(np.mean(h["load"][on] / dcb.propagation_load(cf, h["opening"][on]) - 1))


def test_a_dcb_crack_runs_from_the_fem_into_a_growing_window():
    """dcb_coarse with its window 6 mm ahead of the initial crack (the cohesive zone, 4 mm,
    forms in the FEM and crosses during propagation), the window growing ahead of the crack:
    corrected beam theory's checks hold; every FEM pair from a0 to the band's end failed, and
    every particle pair from the window's first free column to the crack tip, well inside the
    window (no ligament left at the join); the load while the zone crosses is within 3 % of
    beam theory's propagation branch (the case's RMS tolerance is 10 %; a band ending at the
    tied column read 7.4 % over 1 mm of crack); the window grew, its edge undamaged, the FEM
    band's pairs carried over (a pair bonded again would hold the crack shut)."""
    p0 = load_case("dcb_coarse").parameters
    a0, d = p0["geometry.crack_length"], p0["zone.particle_size"]
    x_a = a0 + 6e-3
    c = load_case("dcb_coarse", {"dem.window_start": x_a, "zone.grow": True})
    sim = c.scene.build(c.parameters, "coupled", "liggghts")
    result = None
    try:
        result = run_clock(sim)
    finally:
        (result["simulation"] if result else sim).close()
    h, growth = result["history"], result["simulation"].growth
    qoi, checks = c.scene.evaluate(c.parameters, h, "coupled")
    assert all(ck["passed"] for ck in checks.values()), checks
    fem, inter = growth.built.dyn.node_forces[0].bonds, growth.built.inter
    x_fem, x_dem = fem.X[fem.pairs[:, 0], 0], inter.X[inter.pairs[:, 0], 0]
    tip = float(np.nanmax(h["crack_tip"]))
    assert tip > x_a + 8 * d  # into the window
    assert np.all(fem.damage[x_fem >= a0] == 1.0) and x_fem.max() == pytest.approx(x_a + d / 2)
    assert np.all(inter.damage[(x_dem > x_a + d / 2) & (x_dem <= tip + 1e-9)] == 1.0)
    assert abs(_crossing(p0, h, x_a, qoi["cohesive_zone_bonds"] * d)) < 0.03
    q = growth.qoi()
    assert q["zone_conversions"] >= 1 and max(h["damage_at_zone_edge"]) == 0.0
    assert q["zone_conversion_momentum_jump"] < 1e-12


@pytest.mark.slow  # 25 s
def test_a_growing_window_ahead_of_the_crack_answers_as_the_fixed_one(tmp_path):
    """Grown from ahead of the crack, against the window fixed from t = 0 over the same span:
    the peak load and the dissipation per crack area within 1 %, the crack as far within one
    spacing (measured: 0.004 %, 0.05 %, the same)."""
    x_a = load_case("dcb_coarse").parameters["geometry.crack_length"] + 6e-3
    start = f"--set=dem.window_start={x_a!r}"
    grown, _ = _run(tmp_path, "grown", "dcb_coarse", "--dem", "liggghts", start, "--set=zone.grow=true")
    q = grown["qoi"]
    assert q["zone_conversions"] >= 1
    fixed, _ = _run(tmp_path, "fixed", "dcb_coarse", "--dem", "liggghts", start,
                    f"--set=dem.window_end={q['zone_grown_half_width']!r}")
    for key in ("peak_load", "dissipated_energy_ratio"):
        assert q[key] == pytest.approx(fixed["qoi"][key], rel=0.01), key
    assert abs(q["crack_growth"] - fixed["qoi"]["crack_growth"]) <= grown["parameters"]["zone.particle_size"]


# -m slow: each draw runs the coupled specimen and the all-FEM one (25-60 s)
@pytest.mark.slow
@settings(max_examples=4, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.filter_too_much])
@given(m=MATERIAL, h=THICK, a_rel=st.floats(1.0, 1.6), where=st.floats(0.2, 0.8))
def test_a_dcb_crack_crosses_into_the_window_as_the_all_fem_one_runs(tmp_path_factory, m, h, a_rel, where):
    """Over the ply, the arm and the crack's ranges, the window started anywhere from 20 to 80 %
    of the crack's run: the checks hold, and while the cohesive zone crosses the window's edge
    the load's error against beam theory is the all-FEM specimen's to 2 % (measured at the
    defaults: +1.7 % against +1.3 %), its peak load to 2 %."""
    sets = dcb_sets(m, h, a_rel, 0, 0.25e-3)
    try:
        c = load_case("dcb_coarse", parse_set([a.split("=", 1)[1] for a in sets]))
        p = c.parameters
        warnings = c.scene.validity(p, "coupled") + c.scene.validity(p, "fem")
        a_end = dcb.final_crack_length(p, dcb.closed_form(p))
        x_a = p["geometry.crack_length"] + where * (a_end - p["geometry.crack_length"])
        window_growth.window_start(dict(p, **{"dem.window_start": x_a}), 0.0, dcb.domain(p)[0][1])
    except CaseError:
        assume(False)
    assume(not any(key in w for w in warnings for key in OUTSIDE))
    tmp = tmp_path_factory.mktemp("crossing")
    fem_sets = [a.replace("zone.particle_size", "mesh.element_length") for a in sets if "clock.substeps" not in a]
    fem, hf = _run(tmp, "fem", "dcb_coarse", *fem_sets, "--mode", "fem")  # (the same node spacing)
    d = p["zone.particle_size"]
    zone = fem["qoi"]["cohesive_zone_bonds"] * d
    assume(x_a - zone > p["geometry.crack_length"] + 4 * d)  # the zone formed in the FEM before it crosses
    s, h = _run(tmp, "coupled", "dcb_coarse", *sets, "--dem", "liggghts", f"--set=dem.window_start={x_a!r}")
    assert_checks(s)
    assert_checks(fem)
    assert float(np.nanmax(h["crack_tip"])) > x_a + 4 * d
    gap = _crossing(p, h, x_a, zone) - _crossing(p, hf, x_a, zone)
    event(f"crossing: coupled - all-FEM load error {100 * gap:+.1f} %")  # (--hypothesis-show-statistics)
    assert abs(gap) < 0.02
    assert s["qoi"]["peak_load"] == pytest.approx(fem["qoi"]["peak_load"], rel=0.02)


@pytest.mark.slow  # 30 s and 15 s, and their all-FEM runs
@pytest.mark.parametrize("case, ahead", [("enf_coarse", 6.5e-3), ("mixed_mode_coarse", 6e-3)])
def test_a_bending_crack_starts_in_the_fem_and_runs_into_the_window(tmp_path, case, ahead):
    """ENF (mode II) and SLB (mixed mode) with the window ahead of the initial crack: the
    checks hold, the crack runs through the window, and the peak load (the crack starting in
    the FEM) is the all-FEM specimen's to 1 % (measured: 0.05 % and 0.3 %)."""
    p = load_case(case).parameters
    x_a = p["geometry.crack_length"] + ahead
    s, h = _run(tmp_path, "ahead", case, "--dem", "liggghts", f"--set=dem.window_start={x_a!r}")
    f, _ = _run(tmp_path, "fem", case, "--mode", "fem")
    assert_checks(s)
    assert float(np.nanmax(h["crack_tip"])) > x_a + 8 * p["zone.particle_size"]
    assert s["qoi"]["peak_load"] == pytest.approx(f["qoi"]["peak_load"], rel=0.01)


@pytest.mark.slow  # 30 s
def test_a_crack_crossing_resumes_to_the_uninterrupted_run(tmp_path):
    """Killed after a checkpoint taken while the crack runs in the FEM band (step 38,000 of
    about 60,000: the tip 3 to 5 mm past a0), resumed: the same history, fields and summary,
    bit for bit (the band's pairs are in the FEM's checkpoint)."""
    from test_resume_cases import _femdem, _kill_when, _results, _same
    x_a = load_case("dcb_coarse").parameters["geometry.crack_length"] + 6e-3
    args = ["run", "dcb_coarse", "--dem", "liggghts", "--set", f"dem.window_start={x_a!r}",
            "--set", "output.checkpoint_every=38000"]
    assert (r := _femdem(tmp_path, *args, "--out", "straight")).returncode == 0, r.stderr
    proc = _femdem(tmp_path, *args, "--out", "killed", wait=False)
    assert _kill_when(proc, lambda: (tmp_path / "killed.partial" / "checkpoint" / "state.h5").exists())
    assert (r := _femdem(tmp_path, "run", "--resume", "killed.partial")).returncode == 0, r.stderr
    a, b = _results(tmp_path / "straight"), _results(tmp_path / "killed")
    assert a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)


@pytest.mark.parametrize("sets, says", [
    (["dem.window_start=0.02"], "must start beyond the initial crack tip"),
    (["dem.window_start=0.0548"], "at least 4 particle spacings"),
    (["dem.window_start=0.029", "zone.grow=true"], "must start beyond the initial crack tip"),
])
def test_a_window_start_off_the_crack_s_path_is_refused(femdem, sets, says):
    """Before a0 (a fixed or a growing window), or too close to the window's end: one line
    naming the key, the value and what is allowed (exit 2)."""
    code, _, err = femdem("run", "dcb_coarse", *[f"--set={s}" for s in sets])
    assert code == 2 and err.startswith("femdem: dem.window_start = ") and err.count("\n") == 1, err
    assert says in err
