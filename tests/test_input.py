"""Bad input: one clear line naming key, value and what is allowed; exit code 2; nothing written."""
import re
from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from coupling.params import CaseError, Param, resolve

ROOT = Path(__file__).resolve().parents[1]


def _bad_case(tmp_path, body):
    p = tmp_path / "bad.toml"
    p.write_text('[case]\nscene = "bar_wave"\n' + body)
    return str(p)


@pytest.mark.parametrize("body, words", [
    ("[material]\nrho = -7800.0\n", ["material.rho", "-7800", "> 0"]),
    ("[material]\nyoung = 1e9\n", ["material.young", "unknown key"]),
    ("[mesh]\nelement = 'hex27'\n", ["mesh.element", "hex27", "quad4"]),
    ("[mesh]\nelements_along = 2.5\n", ["mesh.elements_along", "integer"]),
    ("[clock]\ndt = 1.0\n", ["clock.dt", "stable step"]),
])
def test_bad_case_file(femdem, tmp_path, body, words):
    code, summary, err = femdem("run", _bad_case(tmp_path, body))
    assert code == 2 and summary is None
    line = err.strip()
    assert len(line.splitlines()) == 1, line
    for w in words:
        assert w in line, (w, line)
    assert not list(tmp_path.glob("run*")), "nothing may be left behind on bad input"


@pytest.mark.parametrize("args, words", [
    (["--dem", "fluent"], ["--dem fluent", "yade, liggghts, lammps"]),
    (["--set", "material.E=soft"], ["material.E", "soft", "number"]),
    (["--set", "material.E"], ["key=value"]),
    (["--mode", "coupled"], ["--mode coupled", "fem"]),
])
def test_bad_command_line(femdem, args, words):
    code, summary, err = femdem("run", "bar_wave", *args)
    assert code == 2 and summary is None
    assert len(err.strip().splitlines()) == 1
    for w in words:
        assert w in err, (w, err)


def test_unknown_case_and_scene(femdem, tmp_path):
    code, _, err = femdem("run", "no_such_case")
    assert code == 2 and "bundled" in err
    p = tmp_path / "s.toml"
    p.write_text('[case]\nscene = "warp_drive"\n')
    code, _, err = femdem("run", str(p))
    assert code == 2 and "case.scene" in err and "bar_wave" in err


def test_resolved_parameters_round_trip(femdem):
    """Every echoed parameter is accepted back by --set and gives the same resolved set."""
    code, s, _ = femdem("run", "bar_wave", "--set", "mesh.elements_along=60", "--set", "clock.safety=0.8")
    assert code == 0
    sets = sum((["--set", f"{k}={str(v).lower() if isinstance(v, bool) else v}"] for k, v in s["parameters"].items()), [])
    code, s2, _ = femdem("run", "bar_wave", *sets)
    assert code == 0 and s2["parameters"] == s["parameters"]


@given(st.floats(allow_nan=True, allow_infinity=True))
def test_positive_param_accepts_exactly_positive_finite(x):
    p = Param(1.0, kind="float", low=0.0, open_low=True)
    ok = x == x and abs(x) != float("inf") and x > 0
    try:
        assert p.coerce("k", x) == x and ok
    except CaseError as exc:
        assert not ok and "k = " in str(exc)


@given(kind=st.sampled_from(["float", "int", "bool"]), value=st.one_of(st.integers(-10**6, 10**6), st.booleans(),
       st.floats(-1e6, 1e6)))
def test_typed_values_are_taken_as_typed_and_text_only_from_the_command_line(kind, value):
    """A case file's value (typed) is taken only in its own type; the same value as text (--set)
    parses to the same result."""
    p = Param(0, kind=kind)
    own = (kind == "bool") == isinstance(value, bool) and (kind != "int" or isinstance(value, int))
    try:
        assert p.coerce("k", value, typed=True) == value and own
    except CaseError:
        assert not own
    if own:
        assert p.coerce("k", str(value).lower()) == value
    with pytest.raises(CaseError, match="unquoted"):
        p.coerce("k", str(value), typed=True)


@given(st.dictionaries(st.sampled_from(["a.x", "a.y", "b.z", "c.w"]), st.integers(-5, 5)))
def test_resolve_rejects_unknown_and_out_of_range(given_values):
    schema = {"a.x": Param(0, kind="int", low=0), "a.y": Param(0, kind="int"), "b.z": Param(1, kind="int", low=1, high=3)}
    bad = "c.w" in given_values or given_values.get("a.x", 0) < 0 or not 1 <= given_values.get("b.z", 1) <= 3
    try:
        out = resolve(schema, given_values, "test")
        assert not bad and set(out) == set(schema)
    except CaseError:
        assert bad


@pytest.mark.parametrize("setting, words", [
    ("material.rho=7.8", ["material.rho", "implausible", "kg/m^3"]),      # g/cm^3 by mistake
    ("material.E=200000", ["material.E", "implausible", "Pa"]),          # MPa by mistake
])
def test_unit_slips_are_caught(femdem, setting, words):
    code, s, err = femdem("run", "bar_wave", "--set", setting)
    assert code == 2 and s is None
    for w in words:
        assert w in err


@pytest.mark.parametrize("case, args, words", [
    ("cfrp_beam_impact_coarse", ["--set=loads.drop.file=/nonexistent/drop.csv"], ["loads.drop.file", "/nonexistent/drop.csv"]),
    ("cfrp_beam_impact_coarse", ["--set=zone.particle_size=5e-3"], ["zone.particle_size", "whole number"]),
    ("dcb_coarse", ["--set=particle.radius=2e-4"], ["particle.radius", "renamed", "zone.particle_size", "twice"]),
    ("chung_ooi_1", ["--set=particle.radius=0.02"], ["particle.radius", "renamed", "sphere.radius"]),
    ("rod_impact_coarse", ["--set=dem.half_width=0.02"], ["dem.half_width", "renamed", "zone.half_width"]),
    ("cfrp_beam_impact_coarse", ["--set=geometry.span=0.9"], ["geometry.span", "0.9", "<= 0.72"]),
    ("cfrp_beam_impact_coarse", ["--set=zone.half_width=0.5"], ["zone.half_width", "allowed"]),
    ("cfrp_beam_impact_coarse", ["--set=loads.drop.curve=[[0, 0]]"], ["loads.drop.curve", "at least two"]),
    ("cfrp_beam_impact_coarse", ["--set=loads.drop.curve=[[0, 0], [0, 1]]"], ["loads.drop.curve", "increasing"]),
    ("cfrp_beam_impact_coarse", ["--set=loads.drop.curve=oops"], ["loads.drop.curve", "[time, value]"]),
    ("cfrp_beam_impact_coarse", ["--set=supports.pins.condition=clamped"], ["supports", "simply_supported"]),
    ("cfrp_beam_impact_coarse", ["--set=loads.drop.width=0.8"], ["loads.drop.width", "0.8", "<= 0.0508"]),
    ("cfrp_beam_impact_coarse", ["--set=cfrp.T0=1e9"], ["cfrp.T0", "renamed", "materials.cfrp.Xt"]),
    ("cfrp_beam_impact_coarse", ["--set=load.patch_width=0.05"], ["load.patch_width", "renamed", "loads.drop.width"]),
    ("rod_impact_coarse", ["--set=interfaces.table3.penalty=2e10"], ["interfaces.table3.penalty", "toughness"]),
    ("rod_impact_coarse", ["--set=interface.penalty=2e10"], ["interface.penalty", "renamed", "interfaces.table3.penalty"]),
    ("rod_impact_coarse", ["--set=contact.penalty=2e10"], ["contact.penalty", "renamed", "impactors.rod.penalty"]),
    ("rod_impact_coarse", ["--set=fem.integration=selective"], ["fem.integration", "allowed"]),
    ("rod_impact_coarse", ["--mode", "dem"], ["--mode dem", "fem, coupled"]),
    ("rod_impact_coarse", ["--mode", "coupled", "--set=zone.particle_size=0.005"], ["zone.particle_size", "divide"]),
    ("panel_buckling_coarse", ["--mode", "coupled", "--set=zone.window_ahead=0.03"], ["zone.window_ahead", "allowed"]),
    ("panel_buckling_coarse", ["--mode", "coupled", "--set=zone.particle_size=4e-4"], ["zone.particle_size", "allowed"]),
])
def test_bad_input_of_the_seed_scenes(femdem, case, args, words):
    code, summary, err = femdem("run", case, *args)
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)


# -- the catalogue of foreseeable bad input (issue #21): exit 2, one line, nothing written ---------

GOOD = '[case]\nscene = "bar_wave"\n'
CASE_FILES = {  # name: (bytes of the case file, words the one line must hold)
    "latin-1 text": (("# d\xe9j\xe0 vu\n" + GOOD).encode("latin-1"), ["not UTF-8", "0xe9"]),
    "empty": (b"", ["case.scene missing"]),
    "case not a table": (b"case = 5\n", ["case.scene missing"]),
    "scene a number": (b"[case]\nscene = 3\n", ["case.scene = 3", "bar_wave"]),
    "scene a list": (b"[case]\nscene = ['bar_wave']\n", ["case.scene"]),
    "name a list": (GOOD.encode() + b"name = [1]\n", ["case.name = [1]", "string"]),
    "description a table": (GOOD.encode() + b"description = {a = 1}\n", ["case.description", "string"]),
    "name a path": (GOOD.encode() + b"name = '../../etc'\n", ["case.name", "../../etc", "letters"]),
    "name absolute": (GOOD.encode() + b"name = '/tmp/x'\n", ["case.name", "/tmp/x"]),
    "unknown [case] key": (GOOD.encode() + b"mode = 'fem'\n", ["case.mode", "unknown"]),
    "array for a number": (GOOD.encode() + b"[clock]\nsafety = [0.5]\n", ["clock.safety", "[0.5]"]),
    "table for a number": (GOOD.encode() + b"[clock.safety]\nx = 1\n", ["clock.safety.x", "unknown"]),
    "bool for a number": (GOOD.encode() + b"[clock]\nsafety = true\n", ["clock.safety = True", "number"]),
    "string for an int": (GOOD.encode() + b"[output]\nfield_frames = 'ten'\n", ["output.field_frames", "ten", "integer"]),
    "nan": (GOOD.encode() + b"[clock]\nsafety = nan\n", ["clock.safety = nan"]),
    "inf": (GOOD.encode() + b"[clock]\nt_end = inf\n", ["clock.t_end = inf"]),
    "huge int": (GOOD.encode() + b"[output]\nfield_frames = 99999999999999999999\n", ["output.field_frames", "<= 10000"]),
    "fraction for an int": (GOOD.encode() + b"[output]\nfield_frames = 2.5\n", ["output.field_frames = 2.5"]),
    # TOML is typed: a quoted number or switch in a case file is a slip, refused (--set parses text)
    "quoted number": (GOOD.encode() + b"[clock]\nsafety = '0.5'\n", ["clock.safety = '0.5'", "unquoted"]),
    "quoted int": (GOOD.encode() + b"[output]\nfield_frames = \"10\"\n", ["output.field_frames = '10'", "unquoted"]),
    "whole float for an int": (GOOD.encode() + b"[output]\nfield_frames = 10.0\n",
                               ["output.field_frames = 10.0", "integer", "decimal point"]),
    "a date": (GOOD.encode() + b"[clock]\nt_end = 1979-05-27\n", ["clock.t_end", "number"]),
    "duplicated key": (GOOD.encode() + b"[clock]\nsafety = 0.5\nsafety = 0.6\n", ["not valid TOML"]),
    "kinematic tie with a penalty": (b'[case]\nscene = "chain_consistency"\n[coupling]\ntie_penalty = 1e8\n',
                                     ["coupling.tie_penalty", "no effect", "kinematic"]),
    "a renamed key": (b'[case]\nscene = "chain_consistency"\n[interface]\ntie = "penalty"\n',
                      ["interface.tie", "renamed", "coupling.tie"]),
}


@pytest.mark.parametrize("name", CASE_FILES)
def test_bad_case_file_catalogue(femdem, tmp_path, name):
    body, words = CASE_FILES[name]
    path = tmp_path / "bad.toml"
    path.write_bytes(body)
    code, summary, err = femdem("run", str(path))
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
    assert not list(tmp_path.glob("run*")), "nothing may be left behind on bad input"


@pytest.mark.parametrize("old, new, words", [
    (r"E11 = (137.9e9)", r"E11 = '\1'", [".E11 = '137.9e9'", "unquoted"]),
    (r"seed = (1)\n", r"seed = \1.0\n", [".seed = 1.0", "decimal point"]),
    (r"curve = (\[\[.*?\]\])", r"curve = '''\1'''", ["loads.drop.curve", "unquoted"]),
])
def test_a_study_file_s_values_keep_their_toml_type(femdem, tmp_path, old, new, words):
    """A study file's numbers and curves are typed as in any case file: quoted, refused."""
    text = (ROOT / "cases" / "seed" / "cfrp_beam_impact_coarse.toml").read_text()
    text, n = re.subn(old, new, text, count=1, flags=re.S)
    assert n == 1, old  # (the seed file still says it this way)
    path = tmp_path / "quoted.toml"
    path.write_text(text)
    code, summary, err = femdem("run", str(path))
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
    assert not list(tmp_path.glob("run*"))


@pytest.mark.parametrize("encoding", ["utf-8-sig", "utf-16", "utf-32"])
def test_case_files_with_a_byte_order_mark_are_read(femdem, tmp_path, encoding):
    """UTF-8 with a BOM (Windows editors) and UTF-16 / UTF-32, which always carry one, are
    unambiguous: read as their text; the run matches the plain UTF-8 file's."""
    path = tmp_path / "c.toml"
    path.write_bytes((GOOD + "[mesh]\nelements_along = 40\n").encode(encoding))
    code, s, err = femdem("run", str(path))
    assert code == 0, err
    assert s["parameters"]["mesh.elements_along"] == 40


@pytest.mark.parametrize("args, words", [
    (["run", "{tmp}"], ["is a directory"]),
    (["params", ""], ["CASE = ''", "empty"]),
    (["params", " "], ["CASE = ' '", "empty"]),
    (["bench", "", "--sweep", "clock.substeps=1,2"], ["CASE = ''", "empty"]),
    (["run", "{tmp}/missing.toml"], ["no such case file"]),
    (["run", "bar_wave", "--set", "=3"], ["key=value"]),
    (["run", "bar_wave", "--set", "clock.safety="], ["key=value"]),
    (["run", "bar_wave", "--set", "clock.safety=0.5", "--set", "clock.safety=0.6"], ["clock.safety", "twice"]),
    (["run", "bar_wave", "--set", "clock.safety=1e400"], ["clock.safety", "1e400"]),
    (["run", "bar_wave", "--set", "material.E=" + "9" * 401], ["material.E", "number"]),
    (["run", "bar_wave", "--set", "output.field_frames=0x10"], ["output.field_frames", "0x10"]),
    (["run", "bar_wave", "--set", "clock.t_end=1e300"], ["clock.max_steps", "clock steps"]),
    (["run", "bar_wave", "--set", "clock.max_steps=10"], ["clock.max_steps = 10", "clock steps"]),
    (["run", "bar_wave", "--out", "{tmp}/afile"], ["--out", "afile", "exists and is a file"]),
    (["run", "bar_wave", "--out", "{tmp}/afile/sub"], ["--out", "a file"]),
    (["run", "bar_wave", "--dem", "yade"], ["--dem yade", "--mode fem"]),
    (["run", "bar_wave", "--mode", ""], ["--mode", "allowed"]),
    (["run", "bar_wave", "--out", ""], ["--out", "empty"]),
    (["run", "bar_wave", "--set", "clock.dt=5e-324"], ["clock.max_steps", "inf"]),
    (["run", "free_vibration", "--set", "clock.t_end=1e-3"], ["clock.t_end", "run.steps"]),
    (["run", "bar_wave", "--mode", "dem"], ["--mode dem", "fem"]),
    (["run", "bar_wave", "--resume", "{tmp}"], ["--resume", "CASE", "ignored"]),
    (["run", "--resume", "{tmp}", "--set", "a=1"], ["--resume", "--set", "ignored"]),
    (["run", "--resume", "{tmp}", "--dem", "yade"], ["--resume", "--dem", "ignored"]),
    (["run", "--resume", "{tmp}/afile"], ["--resume", "run.json"]),
    (["run", "chain_consistency", "--mode", "dem", "--set", "coupling.tie=penalty"], ["coupling.tie", "no effect"]),
    (["run", "chain_consistency", "--mode", "fem", "--set", "dem.process=worker"], ["dem.process", "no effect"]),
    (["run", "beam_impact_coarse", "--mode", "dem", "--set", "zone.half_width=6e-3"], ["zone.half_width", "no effect"]),
    (["run", "beam_impact_coarse", "--mode", "fem", "--set", "zone.grow=true"], ["zone.grow", "no effect", "--mode fem"]),
    (["run", "beam_impact_coarse", "--mode", "dem", "--set", "zone.placement=auto"], ["zone.placement", "no effect"]),
    (["run", "dcb_coarse", "--mode", "fem", "--set", "zone.grow_at=0.4"], ["zone.grow_at", "no effect", "--mode fem"]),
    (["bench", "beam_impact_coarse", "--mode", "dem", "--set", "zone.grow=true"], ["zone.grow", "no effect", "--mode dem"]),
    (["run", "beam_impact_coarse", "--set", "zone.grow_to=0.05"], ["zone.grow_to = 0.05", "no effect", "zone.grow"]),
    (["run", "cfrp_beam_impact_coarse", "--set", "zone.conversion=release"], ["zone.conversion", "no effect"]),
    (["run", "dcb_coarse", "--set", "zone.grow_every=100"], ["zone.grow_every = 100", "no effect", "zone.grow"]),
    (["run", "beam_impact_coarse", "--set", "zone.margin=1e-3"], ["zone.margin = 0.001", "no effect", "zone.placement"]),
    (["run", "dcb_coarse", "--set", "zone.grow_at=0.3"], ["zone.grow_at = 0.3", "no effect", "zone.grow"]),
    (["run", "dcb_coarse", "--set", "zone.grow=true", "--set", "dem.window_start=0.06"],
     ["dem.window_start = 0.06", "would start at x = 0.072 m", "a smaller dem.window_start"]),
    (["run", "enf_coarse", "--set", "zone.grow=true", "--set", "zone.margin=1e-300", "--set", "dem.window_start=0.0275001"],
     ["dem.window_start = 0.0275001", "1e-07 m apart", "0.05 particle spacing"]),
    (["run", "mixed_mode_coarse", "--set", "zone.grow=true", "--set", "zone.margin=1e-300", "--set",
      "dem.window_start=0.0200001"], ["dem.window_start = 0.0200001", "0.05 particle spacing"]),
    (["run", "beam_impact_coarse", "--set", "zone.half_width=0.0006"], ["zone.half_width = 0.0006", "more than two",
                                                                        "(0.02 m)"]),
    (["run", "dcb_coarse", "--mode", "fem", "--set", "dem.window_start=0.036"], ["dem.window_start", "no effect"]),
    (["run", "chain_consistency", "--set", "dem.ranks=2", "--dem", "yade"], ["dem.ranks = 2", "lammps"]),
    (["run", "chain_consistency", "--set", "zone.particle_size=1e-12"], ["zone.particle_size", "implausible"]),
    (["run", "chain_consistency", "--set", "chain.particles=1000000000"], ["chain.particles", "<= 100000"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0/90]0s"], ["laminates.beam.layup", "repeat 0"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0_0/90]"], ["laminates.beam.layup", "count >= 1"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0/90]s x"], ["laminates.beam.layup", "nothing after"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0//90]"], ["laminates.beam.layup", "ply group"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0_999999999999]"],
     ["laminates.beam.layup", "999999999999 plies", "at most 10000"]),
    (["run", "beam_impact_coarse", "--set", "laminates.beam.layup=[0_6/90_4/0_6]999999999999s"],
     ["laminates.beam.layup", "at most 10000"]),
    (["compare", "chain_consistency", "--dem", "yade,yade"], ["--dem yade,yade", "different"]),
    (["compare", "chain_consistency", "--dem", "yade"], ["--dem yade", "two or more"]),
    (["compare", "bar_wave", "--dem", "yade,liggghts"], ["CASE bar_wave", "all-FEM only"]),
    (["bench", "chain_consistency", "--sweep", "clock.substeps=1,2,-1"], ["clock.substeps", "-1"]),
    (["bench", "chain_consistency", "--sweep", "clock.substeps=1,,2"], ["--sweep", "empty"]),
    (["bench", "chain_consistency", "--sweep", "clock.substeps=1", "--sweep", "clock.substeps=2"], ["twice"]),
    (["bench", "chain_consistency", "--reference-mode", "xyz"], ["--reference-mode xyz"]),
    (["bench", "chain_consistency", "--dem", "yade,yade"], ["--dem yade,yade"]),
])
def test_bad_command_line_catalogue(tmp_path, monkeypatch, capsys, args, words):
    """Each refused in one line before anything runs; bench and compare check every point of
    their sweep first (a bad last value costs nothing). Run from tmp_path: the default run
    directories would land in runs/ there."""
    from coupling.cli import main
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    code = main(args + (["--quiet"] if args[0] == "run" else []))
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
    assert not (tmp_path / "runs").exists()


def test_a_model_too_large_for_the_memory_is_refused_with_its_estimate(femdem):
    """Meshes and lattices are sized before any array of them exists: a mesh of 3e8 nodes is
    refused with its estimate, in one line (exit 2); so is a lattice of 1e15 particles."""
    code, summary, err = femdem("run", "bar_wave", "--set", "mesh.elements_along=100000000")
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1 and "FEM nodes" in err and "GiB" in err and "allowed" in err
    from dem_region.scene import TooLarge, check_fits
    with pytest.raises(TooLarge, match="particles need about"):
        check_fits(1e15, "a lattice")


def test_an_unforeseen_error_is_one_line_and_a_log(monkeypatch, capsys):
    """A defect prints one line with a pointer to its traceback, exit code 1."""
    from coupling import cli

    def boom(args):
        raise ZeroDivisionError("a defect")
    monkeypatch.setattr(cli, "_cases", lambda: boom(None))
    assert cli.main(["cases"]) == 1
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "ZeroDivisionError: a defect" in err and "traceback in" in err
    log = err.split("traceback in ")[1].rstrip(")")
    assert "ZeroDivisionError" in open(log).read()


@pytest.mark.parametrize("run_json, checkpoint, words", [
    ("{\"case_file\": ", None, ["run.json", "corrupt"]),
    ("[1, 2]", None, ["run.json", "corrupt"]),
    ("{\"case_file\": \"x.toml\", \"mode\": \"fem\"}", None, ["run.json", "corrupt", "dem"]),
    (None, None, ["no run.json"]),
    ("VALID", b"not an HDF5 file", ["checkpoint", "corrupt"]),
    ("VALID", b"", ["checkpoint", "corrupt"]),
])
def test_corrupt_run_directories_are_named(tmp_path, capsys, run_json, checkpoint, words):
    """--resume of a directory whose run.json or checkpoint is damaged: one line naming the
    file, exit 2; the directory is left as it was."""
    import json as _json
    from coupling.cli import main
    run = tmp_path / "r.partial"
    run.mkdir()
    if run_json == "VALID":
        run_json = _json.dumps({"case": "bar_wave", "case_file": "bar_wave", "mode": "fem", "dem": "liggghts",
                                "parameters": {}})
    if run_json is not None:
        (run / "run.json").write_text(run_json)
    if checkpoint is not None:
        (run / "checkpoint").mkdir()
        (run / "checkpoint" / "state.h5").write_bytes(checkpoint)
    before = sorted(p.name for p in run.rglob("*"))
    assert main(["run", "--resume", str(run), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
    assert sorted(p.name for p in run.rglob("*")) == before


def test_compare_reports_an_engine_that_errored_as_an_error(tmp_path, monkeypatch, capsys):
    """An engine that failed (status error) makes compare exit 1, not 3 (an instability)."""
    from coupling import compare
    from coupling.cli import main
    real = compare.execute

    def failing(case, mode, engine, out, quiet):
        code, d, s = real(case, mode, engine, out, quiet)
        if engine == "liggghts":
            s = dict(s, status="error", message="RuntimeError: the engine failed")
        return code, d, s
    monkeypatch.setattr(compare, "execute", failing)
    assert main(["compare", "chain_consistency", "--dem", "yade,liggghts", "--out", str(tmp_path / "c")]) == 1
    assert "error" in capsys.readouterr().out


def test_params_lists_every_key_with_its_range_and_round_trips(capsys):
    """`femdem params CASE` prints one line per parameter (key = value  # allowed; meaning) for
    every bundled case, and the printed values, given back as --set, resolve to the same
    parameters (the listing is the case's, in a form the command line accepts)."""
    import ast

    from coupling.case import bundled_cases, load_case
    from coupling.cli import main
    for name in bundled_cases():
        assert main(["params", name]) == 0
        lines = capsys.readouterr().out.splitlines()
        case = load_case(name)
        assert len(lines) == len(case.parameters)
        given = {}
        for line in lines:
            key, rest = line.split(" = ", 1)
            value, comment = rest.split("  # ", 1)
            assert key in case.parameters and comment
            given[key] = str(ast.literal_eval(value))
        assert load_case(name, given).parameters == case.parameters
    assert main(["params", "no_such_case"]) == 2


def test_params_names_the_unit_slip_bounds_it_refuses():
    """Where a key refuses values inside its printed bounds as unit slips (a modulus of 1e5 Pa
    is > 0 but not SI), `femdem params` and the error say so: every value the text allows,
    coerce takes (checked at both ends of the SI band and just outside it)."""
    from coupling.case import COMMON, bundled_cases, load_case
    from coupling.params import CaseError
    seen = 0
    for name in bundled_cases():
        case = load_case(name)
        for key, param in {**COMMON, **case.scene.PARAMETERS}.items():
            if not param.plausible or param.kind != "float":
                continue
            lo, hi = param.plausible
            text = param.allowed()
            narrower = (param.low is None or param.low < lo) or (param.high is None or param.high > hi)
            assert (f"{lo:g} to {hi:g}" in text) == narrower, (name, key, text)
            if narrower:
                seen += 1
                assert param.coerce(key, max(lo, param.low or lo)) is not None
                for slip in [2.0 * hi] + ([0.5 * lo] if lo > 0 else []):
                    with pytest.raises(CaseError):
                        param.coerce(key, slip)
    assert seen  # (the moduli and densities of the scene modules)


def test_a_bench_s_reference_takes_the_compared_runs_zone_settings():
    """--set applies to a bench's runs and its reference alike: a growing zone's keys are the
    coupled runs', and the all-DEM or all-FEM reference takes them without effect (a run of
    its own in those modes refuses them: the catalogue above)."""
    from coupling.bench import sweep_points
    grow = {"zone.grow": "true", "zone.grow_at": "0.4"}
    for ref in ("dem", "fem"):
        points = sweep_points("beam_impact_coarse", {"zone.grow_every": ["0", "1"]}, grow, ref, {}, "liggghts", "coupled")
        assert [s["zone.grow_every"] for _, s in points] == ["0", "1"]



# -- input an audit found accepted (a run that died, or a setting silently ignored): refused at
# load, exit 2, one line naming key, value and what is allowed, nothing written ------------------

BEAM = ROOT / "cases" / "seed" / "beam_impact_coarse.toml"
CFRP = ROOT / "cases" / "seed" / "cfrp_beam_impact_coarse.toml"
SHORT = ["--mode", "fem", "--set", "clock.t_end=1e-6"]  # (the old code ran these: a microsecond)


def _refused(femdem, tmp_path, case, args, words):
    code, summary, err = femdem("run", str(case), *SHORT, *args)
    assert code == 2 and summary is None, err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)
    assert not list(tmp_path.glob("run*")), "nothing may be left behind on bad input"


def _beam_with(tmp_path, tables: str) -> Path:
    path = tmp_path / "beam.toml"
    path.write_text(BEAM.read_text() + "\n" + tables)
    return path


def _cfrp_with_load_file(tmp_path, csv: bytes, keep_curve: bool = False) -> Path:
    """The bonded beam's drop load read from load.csv (ms, kN) beside its copy."""
    text = CFRP.read_text()
    start = text.index("curve = [[0.0")
    end = start if keep_curve else text.index("\n\n", start)
    (tmp_path / "load.csv").write_bytes(csv)
    path = tmp_path / "cfrp.toml"
    path.write_text(text[:start] + 'file = "load.csv"\n' + text[end:])
    return path


STUDY_TABLES = {  # name: (tables appended to the coarse beam, words of the one line)
    "two impactors": ("[impactors.second]\nradius = 5e-3\nmass_per_width = 0.617\nvelocity = 10.0\n",
                      ["[impactors.second]", "[impactors.cylinder]", "one per case"]),
    "two supports": ("[supports.more]\ncondition = 'clamped'\n", ["[supports.more]", "one per case"]),
    "a qoi of two probes": ("[probes.peak_contact_force]\nkind = 'literature_value'\nvalue = 1.0\n",
                            ["probes.contact_force", "probes.peak_contact_force", "'peak_contact_force'"]),
    "a qoi the run records": ("[probes.model_size]\nkind = 'literature_value'\nvalue = 1.0\n",
                              ["probes.model_size", "'model_size'", "the run's own"]),
    "a range upside down": ("[checks.range]\nclosed_form = 'test_between'\nqoi = 'peak_contact_force'\nlow = 5.0\n"
                            "high = 1.0\n", ["checks.range.low = 5", "checks.range.high = 1", "low <= high"]),
    "two durations": ("[clock]\nt_end = 1e-6\n", ["clock.t_end = 1e-06", "case.t_end = 0.0006", "one of them"]),
}


@pytest.mark.parametrize("name", STUDY_TABLES)
def test_tables_that_contradict_the_study_are_refused(femdem, tmp_path, name):
    tables, words = STUDY_TABLES[name]
    path = _beam_with(tmp_path, tables)
    _refused(femdem, tmp_path, path, [], words)
    assert femdem("params", str(path))[0] == 2  # (refused by params too: at load)


@pytest.mark.parametrize("setting, words", [
    ("probes.centre_displacement.x=-1.0", ["probes.centre_displacement.x = -1", "outside", "0 to 0.025"]),
    ("probes.centre_displacement.x=1.0", ["probes.centre_displacement.x = 1", "0 to 0.025"]),
    ("probes.centre_displacement.y=0.5", ["probes.centre_displacement.y = 0.5", "0 to 0.0024"]),
    ("probes.centre_displacement.z=5.0", ["probes.centre_displacement.z = 5", "2D slice", "allowed: 0"]),
    ("fem.hourglass=viscous", ["fem.hourglass = 'viscous'", "no effect", "fem.integration = 'selective'"]),
    ("fem.hourglass=none", ["fem.hourglass = 'none'", "fem.integration = 'reduced'"]),
    ("fem.hourglass_kappa=0.2", ["fem.hourglass_kappa = 0.2", "fem.integration"]),
])
def test_settings_off_the_body_or_without_effect_are_refused(femdem, tmp_path, setting, words):
    """A probe point outside the body was moved to the nearest node (the centre's, the clamp's,
    the top face's value reported); hourglass control without one-point elements changed no bit."""
    _refused(femdem, tmp_path, BEAM, ["--set", setting], words)


def test_probe_points_on_the_body_and_hourglass_with_one_point_elements_are_taken():
    from coupling.case import load_case
    corner = {"probes.centre_displacement.x": "0.025", "probes.centre_displacement.y": "0.0024"}
    assert load_case("beam_impact_coarse", corner).parameters["probes.centre_displacement.x"] == 0.025
    reduced = {"fem.integration": "reduced", "fem.hourglass": "viscous"}
    assert load_case("rod_impact_coarse", reduced).parameters["fem.hourglass"] == "viscous"
    with pytest.raises(CaseError, match=r"outside the disc \(radius 0.12 m\)"):  # a quarter disc: its corner is not
        load_case("rod_impact_coarse", {"probes.plate_deflection.x": "0.1", "probes.plate_deflection.y": "0.1"})


@pytest.mark.parametrize("csv, words", [
    (b"t,F\n0,0\n40,nan\n60,1\n", ["loads.drop.file", "line 3 '40,nan'", "finite"]),
    (b"0,0,5\n1,2,5\n", ["loads.drop.file", "3 columns", "two columns"]),
    ("# d\xe9j\xe0 vu\n0,0\n1,1\n".encode("latin-1"), ["loads.drop.file", "not UTF-8", "0xe9"]),
    (b"t,F\n0,0\nzero,one\n1,1\n", ["loads.drop.file", "'zero,one'", "not numbers"]),
])
def test_a_load_file_is_checked_as_an_inline_curve(femdem, tmp_path, csv, words):
    """NaN passed and the run stopped later blaming its time step; a third column was dropped
    silently; a Latin-1 file gave a bare codec message."""
    _refused(femdem, tmp_path, _cfrp_with_load_file(tmp_path, csv), [], words)


def test_a_load_s_curve_and_file_are_not_both_given(femdem, tmp_path):
    """The file is read instead of the curve: a curve beside it changed nothing."""
    csv = b"time_ms,load_kN\n0,0\n0.2,31.1\n0.4,20\n"
    path = _cfrp_with_load_file(tmp_path, csv)
    _refused(femdem, tmp_path, path, ["--set", "loads.drop.curve=[[0,0],[1e-3,1e30]]"],
             ["loads.drop.curve", "1e+30", "no effect", "loads.drop.file"])
    _refused(femdem, tmp_path, _cfrp_with_load_file(tmp_path, csv, keep_curve=True), [],
             ["loads.drop.curve and loads.drop.file = 'load.csv'", "both given", "one of them"])


@pytest.mark.parametrize("case", ["beam_impact_coarse", "rod_impact_coarse"])
def test_the_hourglass_settings_reach_the_far_field(case):
    """fem.hourglass and fem.hourglass_kappa under reduced integration are the region's (only the
    disc read them: a beam's far field ran the stiffness form at 0.1 whatever the case said)."""
    from coupling.case import load_case
    from coupling.params import parse_set
    c = load_case(case, parse_set(["fem.integration=reduced", "fem.hourglass=viscous", "fem.hourglass_kappa=0.05"]))
    sim, built = c.scene.assemble(c.parameters, "fem", "liggghts")
    try:
        assert (built.dyn.region.hg.form, built.dyn.region.hourglass_kappa) == ("viscous", 0.05)
    finally:
        sim.close()


def test_a_case_file_named_unlike_a_case_is_refused_by_its_file_name(tmp_path):
    """`bar wave.toml` without a case.name: the message names the file (it named case.name, a key
    the user never wrote)."""
    from coupling.case import load_case
    from coupling.params import CaseError
    for source in ("verification/bar_wave.toml", "seed/beam_impact_coarse.toml"):  # a scene's and a study's
        bad = tmp_path / "bar wave.toml"
        bad.write_text((ROOT / "cases" / source).read_text())
        with pytest.raises(CaseError, match=r"^the case file's name 'bar wave.toml' \(its case name, case.name not "):
            load_case(str(bad))
