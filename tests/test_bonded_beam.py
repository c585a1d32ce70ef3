"""A bonded beam written as a case file (issue #23; the seed paper's example 5.4): the
schema's refusals for it, the test-data checks, and its closed-form check over the materials
and loads of its verified ranges (issue #22)."""
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from conftest import ranged_draw

ROOT = Path(__file__).resolve().parents[1]
CFRP = ROOT / "cases" / "seed" / "cfrp_beam_impact_coarse.toml"


def edited(tmp_path, replace: dict, append: str = "") -> Path:
    """The coarse case file with lines replaced ({old line start: new line or ''}) and text appended."""
    lines = CFRP.read_text().splitlines()
    for old, new in replace.items():
        hit = [i for i, line in enumerate(lines) if line.startswith(old)]
        assert hit, old
        lines[hit[0]] = new
    path = tmp_path / "bonded.toml"
    path.write_text("\n".join(lines) + "\n" + append)
    return path


@pytest.mark.parametrize("replace, append, words", [
    ({"material = \"concrete\"": 'material = "cfrp"'}, "", ["geometry.material", "isotropic"]),
    ({"depth = ": ""}, "", ["geometry.depth", "required"]),
    ({"particle_size = ": ""}, "", ["zone.particle_size", "required"]),
    ({}, "\n[laminates.extra]\nlayup = \"[0]\"\nply_thickness = 1e-3\nmaterial = \"cfrp\"\ninterface = \"adhesive\"\n",
     ["laminates.extra", "takes none"]),
    ({'material = "cfrp"': 'material = "concrete"'}, "", ["sheets.cfrp.material", "ply"]),
    ({"E = 24e9": "E = 24e9\nE11 = 3e9"}, "", ["materials.concrete.E11", "unknown key"]),
    ({"curve = ": "curve = [[0.0, 1.0], [0.0, 2.0]]", "         [1.0": "", "         [2.6": ""}, "",
     ["loads.drop.curve", "increasing"]),
])
def test_a_bad_bonded_beam_is_refused_in_one_line(femdem, tmp_path, replace, append, words):
    assert femdem("params", str(edited(tmp_path, {})))[0] == 0  # the file as given is valid
    code, s, err = femdem("params", str(edited(tmp_path, replace, append)))
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, err


def test_a_load_wider_than_the_span_is_refused_when_no_range_refuses_it(femdem, tmp_path):
    """Without the case's [ranges] (a user's own file), a patch as wide as the span is refused
    by the assembly, before anything is written."""
    text = CFRP.read_text()
    path = tmp_path / "wide.toml"
    path.write_text(text[: text.index("[ranges]")])
    code, s, err = femdem("run", str(path), "--set=loads.drop.width=0.8")
    assert code == 2 and s is None and "loads.drop.width" in err and "narrower than the span" in err, err


def test_a_load_file_is_read_relative_to_its_case_file(femdem, tmp_path):
    """loads.*.file: a CSV beside the case file, in the curve's units (ms, kN here); the all-FEM
    beam under it equals the one under the same curve written inline."""
    (tmp_path / "drop.csv").write_text("time_ms,load_kN\n0,0\n0.2,31.1\n0.3,35.6\n0.4,31.1\n0.5,28.9\n")
    path = edited(tmp_path, {"curve = ": 'file = "drop.csv"', "         [1.0": "", "         [2.6": ""})
    short = ["--set=clock.t_end=0.4e-3"]
    code, s_file, err = femdem("run", str(path), "--mode", "fem", *short)
    assert code == 0, err
    inline = "[[0.0, 0.0], [0.2, 31.1], [0.3, 35.6], [0.4, 31.1], [0.5, 28.9]]"
    code, s_curve, err = femdem("run", "cfrp_beam_impact_coarse", "--mode", "fem", *short,
                                f"--set=loads.drop.curve={inline}")
    assert code == 0, err
    assert s_file["parameters"]["loads.drop.file"] == str(tmp_path / "drop.csv")
    assert s_file["qoi"]["peak_midspan_displacement"] == s_curve["qoi"]["peak_midspan_displacement"]
    assert 0.99 * 35.6e3 < s_file["qoi"]["peak_load"] <= 35.6e3 * (1 + 1e-12)  # sampled near the 0.3 ms peak


def test_test_data_checks_compare_with_the_values_in_the_file():
    """test_value within tol, test_between inside [low, high], a missing qoi not checked; the
    references come from the case file, not from a run."""
    from coupling.case import load_case
    from coupling.study import closed_forms
    case = load_case(str(CFRP))
    p, study = case.parameters, case.scene
    h = {"balance_error_rel": [0.0]}
    ok = {"crack_initiation_time": 430e-6 * 1.2, "debond_initiation_time": 470e-6 * 0.7,
          "crack_top_time": 500e-6, "debonded_fraction_750us": 0.05}
    checks = closed_forms.evaluate(study, p, dict(ok), h)
    assert checks["crack_initiation_time"]["passed"] and checks["crack_initiation_time"]["reference"] == 430e-6
    assert not checks["debond_initiation_time"]["passed"]  # 30 % off, tol 25 %
    assert checks["crack_top_time"]["passed"] and checks["crack_top_time"]["reference"] == [460e-6, 750e-6]
    assert not checks["debonded_fraction_750us"]["passed"]  # below 0.1
    assert "crack_onset_time" not in checks  # its qoi is not in this run: the FEM twin is not run
    assert "Jerome & Ross" in checks["crack_initiation_time"]["source"]


@settings(max_examples=1, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture])  # (one draw: the suite's budget)
@given(sets=ranged_draw("cfrp_beam_impact_coarse"))
def test_cracking_starts_when_the_elastic_beam_reaches_ft_over_its_ranges(femdem, sets):
    """Coupled, anywhere in the case's [ranges] (the concrete, the sheet, the adhesive, the
    load and the beam's dimensions, every key drawn at once): the first bond softens within 20 %
    of the time the no-fracture all-FEM beam's bottom fibre reaches (1 - scatter) ft (the case's
    own check), the ledger closes, and nothing is warned as not verified."""
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", *sets)
    assert code == 0, err
    c, q = s["checks"], s["qoi"]
    assert c["energy_balance"]["passed"], c
    assert math.isfinite(q["elastic_cracking_time"]), q
    assert c["crack_onset_time"]["passed"], (sets, c["crack_onset_time"])
    assert np.isfinite(q["peak_midspan_displacement_no_fracture"])
    assert not [w for w in s["warnings"] if "not verified" in w], s["warnings"]


@pytest.mark.slow
@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(dem=st.sampled_from(["liggghts", "lammps", "yade"]), sets=ranged_draw("cfrp_beam_impact_coarse"))
def test_cracking_onset_over_its_ranges_on_every_engine(femdem, dem, sets):
    """The same check, random draws, on the three engines (-m slow)."""
    code, s, err = femdem("run", "cfrp_beam_impact_coarse", "--dem", dem, *sets)
    assert code == 0, err
    assert s["checks"]["energy_balance"]["passed"] and s["checks"]["crack_onset_time"]["passed"], (sets, s["checks"])


@pytest.mark.slow
@settings(max_examples=3, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(dem=st.sampled_from(["liggghts", "lammps", "yade"]), sets=ranged_draw("cfrp_beam_impact_3d_coarse"))
def test_the_3d_beam_cracks_on_time_over_its_ranges(femdem, dem, sets):
    """The 3D quarter beam (cfrp_beam_impact_3d_coarse, the 2D case's [ranges])
    over its ranges: the crack-onset check and the ledger hold on the three engines (-m slow)."""
    code, s, err = femdem("run", "cfrp_beam_impact_3d_coarse", "--dem", dem, *sets)
    assert code == 0, err
    assert s["checks"]["energy_balance"]["passed"] and s["checks"]["crack_onset_time"]["passed"], (sets, s["checks"])
