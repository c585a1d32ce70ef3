"""femdem bench's faults: a cached reference reused though a file its case reads had changed,
and points whose error was nan (a quantity never reached) printed as Pareto-optimal."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from coupling import bench
from coupling.case import load_case
from coupling.cli import main

STUDIES = Path(__file__).resolve().parent / "studies"


def pressed_block(folder: Path, peak_kN: float) -> Path:
    """tests/studies/pressed_block.toml with its pressure history read from press.csv (a ramp to
    peak_kN over 40 us, then held) and its Gmsh mesh copied beside it: both files relative to
    the case file, as a user's own study would name them."""
    text = (STUDIES / "pressed_block.toml").read_text()
    curve = next(line for line in text.splitlines() if line.startswith("curve ="))
    (folder / "pressed.toml").write_text(text.replace(curve, 'file = "press.csv"'))
    (folder / "gmsh_block.msh").write_bytes((STUDIES / "gmsh_block.msh").read_bytes())
    write_load(folder, peak_kN)
    return folder / "pressed.toml"


def write_load(folder: Path, peak_kN: float) -> None:
    (folder / "press.csv").write_text(f"time,force\n0,0\n40,{peak_kN}\n1000,{peak_kN}\n")  # us, kN


@pytest.fixture
def fake_runs(monkeypatch, tmp_path):
    """bench.execute replaced by a run that returns at once; the list of the cases it ran."""
    ran = []

    def execute(case, mode, dem, out, quiet=True):
        ran.append(case)
        return 0, None, {"qoi": {"peak_load": 1.0}, "timing_s": {"total": 1.0, "plots": 0.1}, "status": "ok",
                         "message": ""}

    monkeypatch.setattr(bench, "execute", execute)
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    return ran


def test_a_reference_cached_with_its_plots_in_its_wall_runs_again(tmp_path, fake_runs):
    """A reference cached before runs booked their plots apart (no timing_s.plots) has them in
    its wall time, the points not: it runs again, and the new one is cached."""
    reference = lambda k: bench.reference("chain_consistency", {}, "fem", "yade", tmp_path / f"ref{k}")[1]
    assert reference(0) is False
    (cached,) = (tmp_path / "cache" / "references").glob("*.json")
    summary = json.loads(cached.read_text())
    del summary["timing_s"]["plots"]
    cached.write_text(json.dumps(summary))
    assert [reference(1), reference(2)] == [False, True] and len(fake_runs) == 2


def test_a_reference_runs_again_when_a_file_its_case_reads_changes(tmp_path, fake_runs):
    """The auditor's repro: a load CSV's forces x10 reused the reference run with the old ones
    (a max rel. error of 9). Every file a parameter names is part of the cache's key: a changed
    load curve or mesh is a new reference; the same bytes written again are not."""
    case = pressed_block(tmp_path, 0.7)
    reference = lambda k: bench.reference(str(case), {}, "fem", "yade", tmp_path / f"ref{k}")[1]
    assert [reference(0), reference(1)] == [False, True]
    write_load(tmp_path, 7.0)
    assert [reference(2), reference(3)] == [False, True]
    write_load(tmp_path, 7.0)  # rewritten, same contents: the cache holds
    assert reference(4) is True
    with open(tmp_path / "gmsh_block.msh", "ab") as f:
        f.write(b"\n")
    assert reference(5) is False
    assert len(fake_runs) == 3


def test_the_key_reads_the_files_the_case_names_and_survives_a_missing_one(tmp_path):
    from coupling.case import input_digests
    case = load_case(str(pressed_block(tmp_path, 0.7)))
    assert set(input_digests(case.path, case.parameters)) == {"case_file", "mesh.file", "loads.press.file"}
    before = bench._key(case, "fem", "yade")
    (tmp_path / "press.csv").unlink()  # (removed after loading: the run then says so)
    assert input_digests(case.path, case.parameters)["loads.press.file"] == "unreadable"
    assert bench._key(case, "fem", "yade") != before


def test_an_edited_case_file_is_another_reference(tmp_path):
    """The case file's own contents count too: a probe or check added to it changes the
    reference's qoi, though not its parameters."""
    path = pressed_block(tmp_path, 0.7)
    before = bench._key(load_case(str(path)), "fem", "yade")
    path.write_text(path.read_text() + "\n# edited\n")
    assert bench._key(load_case(str(path)), "fem", "yade") != before


def test_a_point_whose_error_is_not_finite_is_never_pareto_optimal():
    nan, inf = float("nan"), float("inf")
    times = np.array([1.0, 2.0, 3.0, 0.5, 0.1])
    errors = np.array([nan, 0.1, 0.05, inf, 0.2])
    assert list(bench.pareto(times, errors)) == [1, 2, 4]
    assert list(bench.pareto(np.array([1.0, 2.0]), np.array([nan, nan]))) == []


def test_relative_errors_say_why_a_quantity_is_not_compared():
    """bar_wave at t_end = 10 us: the reference's wave reaches neither station, a coarse mesh's
    reaches the near one (its front is smeared ahead). nan - nan was the nan printed; now each
    quantity says why it has no relative error, and a quantity reached in one run only leaves
    the point without a max error."""
    nan = float("nan")
    ref = {"wave_speed": nan, "arrival_time_near": nan, "arrival_time_far": nan}
    coarse = {"wave_speed": nan, "arrival_time_near": 9.3e-6, "arrival_time_far": nan}
    errors, why, one_sided = bench.relative_errors(list(ref), coarse, ref)
    assert errors == {} and one_sided
    assert why == {"wave_speed": "reached in neither run", "arrival_time_near": "not reached in the reference",
                   "arrival_time_far": "reached in neither run"}
    errors, why, one_sided = bench.relative_errors(["a", "b", "c", "d", "e"],
                                                   {"a": 1.1, "b": 0.0, "c": 2.0, "d": None, "e": nan},
                                                   {"a": 1.0, "b": 0.0, "c": 0.0, "d": 3.0, "e": nan})
    assert errors == {"a": pytest.approx(0.1), "b": 0.0} and one_sided
    assert why == {"c": "0 in the reference", "d": "not reached in this run", "e": "reached in neither run"}
    errors, why, one_sided = bench.relative_errors(["a", "e"], {"a": 1.1, "e": nan}, {"a": 1.0, "e": nan})
    assert list(errors) == ["a"] and not one_sided and all(math.isfinite(e) for e in errors.values())


def test_bar_wave_before_its_wave_arrives_prints_no_nan_and_no_pareto(tmp_path, monkeypatch, capsys):
    """The repro: bench bar_wave at t_end = 10 us printed "max rel. error nan (Pareto)" for every
    point."""
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    assert main(["bench", "bar_wave", "--sweep", "mesh.elements_along=10,20", "--mode", "fem",
                 "--reference-mode", "fem", "--set", "clock.t_end=1e-5", "--out", str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    r = json.loads((tmp_path / "b" / "speed_error.json").read_text())
    assert "nan" not in out.replace("not reached", "")
    for p in r["points"]:
        error = p["max_rel_error"]
        assert error is None or math.isfinite(error)
        assert not p.get("pareto") or error is not None
        assert all(math.isfinite(e) for e in p["rel_error"].values())
    lines = [line for line in out.splitlines() if "mesh.elements_along" in line]
    assert len(lines) == 2 and all("(Pareto)" not in line for line in lines if "n/a" in line)
    assert all("not compared: " in line for line in lines if "n/a" in line)


def test_a_reference_mode_the_case_lacks_is_named_as_that_option(tmp_path, capsys):
    """bench with no flags: the default reference (--reference-mode dem) was refused as
    "--mode dem"."""
    assert main(["bench", "bar_wave", "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert "--reference-mode dem: case bar_wave supports fem" in err
    assert main(["bench", "bar_wave", "--reference-mode", "fem", "--out", str(tmp_path / "b")]) == 2
    assert "--mode coupled: case bar_wave supports fem" in capsys.readouterr().err


def test_a_value_swept_twice_is_refused_by_its_option():
    """--sweep k=10,10 was blamed on --out (the second point's directory existed)."""
    from coupling.bench import parse_sweep
    from coupling.params import CaseError
    with pytest.raises(CaseError, match=r"--sweep mesh.elements_along=10,20,10: 10 given twice"):
        parse_sweep(["mesh.elements_along=10,20,10"])
    assert parse_sweep(["mesh.elements_along=10,20"]) == {"mesh.elements_along": ["10", "20"]}


def test_compare_s_differences_and_json_say_what_cannot_be_compared(tmp_path):
    """compare.json held a bare NaN (not JSON: strict readers refuse it) and its max_rel_diff read 0
    whenever the first engine's value was 0. Now: None (null, printed n/a) where no relative
    difference is a number, and the file is strict JSON."""
    from coupling.compare import max_rel_diff
    from coupling.output import write_json
    assert max_rel_diff({"a": 2.0, "b": 2.5}, "a") == pytest.approx(0.25)
    assert max_rel_diff({"a": 0.0, "b": 1e-3}, "a") is None and max_rel_diff({"a": 0.0, "b": 0.0}, "a") == 0.0
    assert max_rel_diff({"a": float("nan"), "b": 1.0}, "a") is None and max_rel_diff({"a": 1.0, "b": None}, "a") is None
    path = tmp_path / "x.json"
    write_json(path, {"v": float("nan"), "w": [1.0, float("inf")], "p": tmp_path})
    assert json.loads(path.read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}")) == \
        {"v": None, "w": [1.0, None], "p": str(tmp_path)}


def test_a_bench_leaves_the_kernels_compilation_out_of_its_wall_times(monkeypatch, tmp_path):
    """A fresh machine's first reference run compiled the parallel ply pass: 62 s where its
    rounds took 43-55, and the speedup read 5.3 x for 4.9. Each run's wall time is its total
    less its compile seconds (kept beside it), the speedups the ratios of those."""
    totals = iter([(62.0, 20.0), (8.5, 0.0), (43.0, 0.0), (8.6, 0.3)])  # (total, compile) in run order

    def execute(case, mode, dem, out, quiet=True):
        total, compile_s = next(totals)
        return 0, None, {"qoi": {"peak_load": 1.0}, "timing_s": {"total": total, "compile": compile_s},
                         "status": "ok", "message": ""}

    monkeypatch.setattr(bench, "execute", execute)
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    r = bench.bench("chain_consistency", {"clock.substeps": ["2"]}, {}, "fem", {}, "liggghts", "coupled",
                    tmp_path / "b", None, 2)
    assert r["reference"]["wall_s_runs"] == [42.0, 43.0]
    assert r["reference"]["compile_s_runs"] == [20.0, 0.0]
    p = r["points"][0]
    assert p["wall_s_runs"] == [8.5, pytest.approx(8.3)] and p["compile_s_runs"] == [0.0, 0.3]
    assert p["speedup"] == pytest.approx(np.median([42.0 / 8.5, 43.0 / 8.3]))


def test_a_bench_leaves_the_plots_drawing_out_of_its_wall_times(monkeypatch, tmp_path):
    """Each run draws its plots from its finished history in half a second to a second, whatever
    the model: a tenth of a 4 s coupled run, a sixtieth of a 31 s all-DEM one. The wall times
    are the totals less compile and plot seconds, both kept beside."""
    runs = iter([(40.0, 0.0, 1.2), (5.0, 0.5, 1.0), (41.0, 0.0, 1.1), (5.2, 0.0, 0.9)])  # (total, compile, plots)

    def execute(case, mode, dem, out, quiet=True):
        total, compile_s, plots = next(runs)
        return 0, None, {"qoi": {"peak_load": 1.0}, "timing_s": {"total": total, "compile": compile_s, "plots": plots},
                         "status": "ok", "message": ""}

    monkeypatch.setattr(bench, "execute", execute)
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path / "cache"))
    r = bench.bench("chain_consistency", {"clock.substeps": ["2"]}, {}, "fem", {}, "liggghts", "coupled",
                    tmp_path / "b", None, 2)
    assert r["reference"]["wall_s_runs"] == [pytest.approx(38.8), pytest.approx(39.9)]
    assert r["reference"]["plots_s_runs"] == [1.2, 1.1]
    p = r["points"][0]
    assert p["wall_s_runs"] == [pytest.approx(3.5), pytest.approx(4.3)] and p["plots_s_runs"] == [1.0, 0.9]
    assert p["speedup"] == pytest.approx(np.median([38.8 / 3.5, 39.9 / 4.3]))


def test_a_run_books_its_plots_within_its_io_and_total(femdem, tmp_path):
    """timing_s.plots: the seconds drawing plots/*.png, inside the io bucket and the total; the
    wall time bench and compare read is the total less it and the compile seconds."""
    from coupling.run import wall_s
    code, s, err = femdem("run", "chain_consistency")
    assert code == 0, err
    t = s["timing_s"]
    assert list((tmp_path / "run0" / "plots").glob("*.png")), "no plot drawn"
    assert 0.0 < t["plots"] <= t["io"] <= t["total"], t
    assert wall_s(s) == pytest.approx(t["total"] - t["compile"] - t["plots"])


def test_compare_sets_the_engines_wall_times_side_by_side_without_compiling(monkeypatch, tmp_path):
    """The first engine of a comparison on a new machine compiles the kernels the others load:
    compare.json's wall time per engine is each run's total less its compile (and plot) seconds."""
    from coupling import compare
    real = compare.execute

    def compiled(case, mode, engine, out, quiet):
        code, d, s = real(case, mode, engine, out, quiet)
        extra = 30.0 if engine == "yade" else 0.0  # (as if its process had compiled for 30 s)
        t = dict(s["timing_s"], total=s["timing_s"]["total"] + extra, compile=s["timing_s"]["compile"] + extra)
        return code, d, dict(s, timing_s=t)
    monkeypatch.setattr(compare, "execute", compiled)
    r = compare.compare("chain_consistency", ["yade", "liggghts"], {}, None, tmp_path / "c")
    for e in ("yade", "liggghts"):
        t = json.loads((tmp_path / "c" / e / "summary.json").read_text())["timing_s"]
        assert r["wall_s"][e] == pytest.approx(t["total"] - t["compile"] - t["plots"])
    assert r["compile_s"]["yade"] >= 30.0 and r["wall_s"]["yade"] < 30.0
