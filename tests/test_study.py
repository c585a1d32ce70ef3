"""Studies written as case files (issue #23): the schema's one-line errors, a new study that
exists only as a TOML file run in every mode on every engine against its closed form, and the
seed beam's study over its verified ranges."""
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from conftest import assert_checks

ROOT = Path(__file__).resolve().parents[1]
BEND = ROOT / "tests" / "studies" / "three_point_bend.toml"


def study_text(**replace) -> str:
    """The three-point bend's text with lines replaced: {old line start: new line or ''}."""
    lines = BEND.read_text().splitlines()
    for old, new in replace.items():
        hit = [i for i, line in enumerate(lines) if line.startswith(old)]
        assert hit, old
        lines[hit[0]] = new
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("replace, extra, words", [
    ({"E22 = ": ""}, "", ["materials.t300_914.E22", "required"]),
    ({"E22 = ": "E22 = -1.0"}, "", ["materials.t300_914.E22", "> 0"]),
    ({"E22 = ": "E2 = 8e9"}, "", ["materials.t300_914.E2", "unknown key"]),
    ({"material = ": 'material = "steel"'}, "", ["laminates.crossply.material", "steel", "t300_914"]),
    ({"impactor = ": 'impactor = "hammer"'}, "", ["probes.contact_force.impactor", "hammer", "striker"]),
    ({"kind = \"contact_force\"": 'kind = "strain_gauge"'}, "", ["probes.contact_force.kind", "strain_gauge"]),
    ({"closed_form = ": 'closed_form = "euler"'}, "", ["checks.peak_deflection.closed_form", "beam_spring_mass"]),
    ({"qoi = ": 'qoi = "peak_stress"'}, "", ["checks.peak_deflection.qoi", "peak_stress", "no probe"]),
    ({"t_end = ": ""}, "", ["case.t_end", "required"]),
    ({"fix = ": 'fix = "x"'}, "", ["supports.rollers.fix", "'xy'", "'y'"]),
    ({}, "[loads]\nforce = 1.0\n", ["[loads]", "unknown table"]),
    ({}, '[ranges]\n"geometry.span" = [50e-3, 80e-3]\n', ["geometry.span", "0.04", ">= 0.05"]),
    ({}, '[ranges]\n"geometry.spam" = [50e-3, 80e-3]\n', ["ranges.geometry.spam", "not a numeric key"]),
])
def test_a_bad_study_is_refused_in_one_line(tmp_path, replace, extra, words):
    from coupling.case import load_case
    from coupling.params import CaseError
    path = tmp_path / "study.toml"
    path.write_text(study_text(**replace) + extra)
    with pytest.raises(CaseError) as err:
        load_case(str(path))
    line = str(err.value)
    assert "\n" not in line and all(w in line for w in words), line


@pytest.mark.parametrize("key, value, words", [
    ("material.E11", "1e11", ["renamed", "materials.t300_914.E11"]),
    ("impactor.velocity", "3", ["renamed", "impactors.striker.velocity"]),
    ("dem.half_width", "0.01", ["renamed", "zone.half_width"]),
    ("interface.R0", "1e7", ["renamed", "interfaces.epoxy.R0"]),
    ("interface.tie", "penalty", ["renamed", "coupling.tie"]),
    ("impactors.striker.shape", "sphere", ["one of 'cylinder'"]),
    ("probes.deflection.kind", "contact_force", ["says what the table is"]),
    ("laminates.crossply.material", "steel", ["one of 't300_914'"]),
])
def test_old_and_structural_keys_are_refused_with_what_to_do(key, value, words):
    from coupling.case import load_case
    from coupling.params import CaseError
    with pytest.raises(CaseError) as err:
        load_case(str(BEND), {key: value})
    assert all(w in str(err.value) for w in words), str(err.value)


def test_a_bad_study_exits_2_before_anything_is_written(tmp_path):
    path = tmp_path / "study.toml"
    path.write_text(study_text(**{"E22 = ": ""}))
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-m", "coupling.cli", "run", str(path), "--out", str(out)], cwd=tmp_path,
                       capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "Traceback" not in r.stderr, r.stderr
    assert not out.exists()


def test_the_schema_is_documented_and_docs_cases_md_is_its_output():
    """`femdem schema` names every table and key the assembler reads; docs/cases.md is that
    text (regenerate: femdem schema > docs/cases.md, inside its fence)."""
    from coupling.study import document_schema
    from coupling.study.schema import KINDS, LAMINATE, SECTIONS
    text = document_schema()
    for fields in [*SECTIONS.values(), LAMINATE, *(f for kinds in KINDS.values() for f in kinds.values())]:
        for key in fields:
            assert f"  {key} = " in text, key
    assert text in (ROOT / "docs" / "cases.md").read_text()


ENGINES = ["liggghts", "lammps", "yade"]


@pytest.mark.parametrize("mode, dem", [("fem", None), *[("coupled", e) for e in ENGINES], *[("dem", e) for e in ENGINES]])
def test_a_study_written_only_as_a_case_file_runs_everywhere(femdem, mode, dem):
    """The three-point bend (tests/studies/): every mode on every engine; the peak deflection
    against the spring-mass closed form of a simply supported beam, the ledger closed."""
    code, s, err = femdem("run", str(BEND), "--mode", mode, *(["--dem", dem] if dem else []))
    assert code == 0, err
    assert_checks(s)
    assert s["scene"] == "three_point_bend" and s["parameters"]["materials.t300_914.E11"] == 130e9


def test_the_coupled_study_equals_its_all_fem_beam(femdem):
    """Nothing breaks at 2 m/s: the coupled beam (zone + tie) and the all-FEM beam give the
    same peak deflection within 3 %."""
    peaks = {}
    for mode in ("fem", "coupled"):
        code, s, err = femdem("run", str(BEND), "--mode", mode)
        assert code == 0, err
        peaks[mode] = s["qoi"]["peak_deflection"]
        assert s["qoi"].get("delamination_length_0", 0.0) == 0.0
    assert abs(peaks["coupled"] / peaks["fem"] - 1) < 0.03


@settings(max_examples=2, deadline=None, derandomize=True, phases=[Phase.explicit, Phase.generate],
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(E11=st.floats(60e9, 200e9), E22=st.floats(6e9, 12e9), span=st.floats(30e-3, 60e-3),
       velocity=st.floats(0.5, 3.0), layup=st.sampled_from(["[0_2/90_2]s", "[90_2/0_2]s", "[0_4/90_2]s"]))
def test_the_study_holds_its_closed_form_for_other_materials_and_layups(femdem, E11, E22, span, velocity, layup):
    code, s, err = femdem("run", str(BEND), "--mode", "coupled", f"--set=materials.t300_914.E11={E11}",
                          f"--set=materials.t300_914.E22={E22}", f"--set=geometry.span={span}",
                          f"--set=impactors.striker.velocity={velocity}", f"--set=laminates.crossply.layup={layup}",
                          f"--set=clock.t_end={0.5e-3 * (span / 40e-3) ** 2 * (130e9 / E11) ** 0.5}")
    assert code == 0, err
    assert_checks(s)


def test_the_readme_case_file_runs(femdem, tmp_path):
    """The case file README "Using it" shows is a working study (all-FEM, to 0.1 ms)."""
    text = (ROOT / "README.md").read_text()
    body = text.split("```toml\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "my_beam.toml"
    path.write_text(body)
    code, s, err = femdem("run", str(path), "--mode", "fem", "--set=clock.t_end=1e-4")
    assert code == 0, err
    assert s["qoi"]["peak_centre_displacement"] > 0 and s["checks"]["energy_balance"]["passed"]
