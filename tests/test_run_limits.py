"""The limits of a run: a history too sparse to read qoi from, quantities at moments after the
run ended, a test with nothing to test. Each is refused as bad input (exit 2, one line naming
the key) or reported as not reached, never as a number that looks real."""
from __future__ import annotations

import math
import shutil

import pytest

from conftest import SEED_CASES


def _one_line_refusal(code, summary, err, *words):
    assert code == 2, err
    assert summary is None  # nothing written
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "Warning" not in err
    for word in words:
        assert word in lines[0], err


@pytest.mark.parametrize("case", ["bar_wave", "block_impact"])
def test_history_every_leaving_too_few_samples_is_refused(femdem, case):
    # bar_wave divided by zero, block_impact reported a 0 N peak with status ok
    code, summary, err = femdem("run", case, "--set", "output.history_every=100000")
    _one_line_refusal(code, summary, err, "output.history_every = 100000", "clock steps", "allowed: 0")


def test_history_every_at_the_limit_runs(femdem):
    # block_impact's default run is 541 clock steps: every 60 gives 10 samples after t = 0, 61 gives 9
    code, _, err = femdem("run", "block_impact", "--set", "output.history_every=61")
    _one_line_refusal(code, None, err, "541 clock steps", "1 to 60")
    code, summary, err = femdem("run", "block_impact", "--set", "output.history_every=60")
    assert code == 0, err
    assert summary["qoi"]["peak_contact_force"] > 0.0


def test_history_every_a_case_overrides_is_refused(femdem):
    code, summary, err = femdem("run", "chung_ooi_1", "--set", "output.history_every=5")
    _one_line_refusal(code, summary, err, "output.history_every = 5", "has no effect", "allowed: 0")


def test_peak_at_the_runs_last_sample_is_warned(femdem, tmp_path):
    # 60 us: the beam's centre still moving down when the run ends; the reported peak is not one
    case = tmp_path / "case.toml"
    shutil.copy(SEED_CASES / "beam_impact_coarse.toml", case)
    code, summary, err = femdem("run", str(case), "--mode", "fem", "--set", "clock.t_end=6e-5")
    assert code == 0, err
    assert summary["qoi"]["time_of_peak_centre_displacement"] == pytest.approx(6e-5)
    said = [w for w in summary["warnings"] if "peak_centre_displacement" in w]
    assert said and "last sample" in said[0] and "before the peak" in said[0], summary["warnings"]
    assert "last sample" in err


def test_quantity_at_a_time_after_the_run_is_not_reported(femdem):
    # debonded_fraction_750us of a run that ended at 10 us: null, its check failed (was 0.0)
    code, summary, err = femdem("run", "cfrp_beam_impact_coarse", "--set", "clock.t_end=1e-5")
    assert code == 0, err
    assert summary["qoi"]["debonded_fraction_750us"] is None
    assert not summary["checks"]["debonded_fraction_750us"]["passed"]


def test_contact_still_on_at_the_end_has_no_duration(femdem):
    # the spheres still pressed together at 1 us (Hertz t_c ~ 40 us): was 1e-06 s
    code, summary, err = femdem("run", "chung_ooi_1", "--set", "clock.t_end=1e-6")
    assert code == 0, err
    assert summary["qoi"]["contact_duration"] is None
    assert not summary["checks"]["contact_duration"]["passed"]


def test_probe_readings_past_the_end():
    from coupling.study.probes import at_time, peak_at_end
    time = [0.0, 1.0, 2.0]
    assert at_time(1.5, time, [0.0, 2.0, 4.0]) == pytest.approx(3.0)
    assert at_time(2.0, time, [0.0, 2.0, 4.0]) == pytest.approx(4.0)
    assert math.isnan(at_time(2.5, time, [0.0, 2.0, 4.0]))
    assert peak_at_end("u", {"time": time, "u": [0.0, 1.0, 2.0]})
    assert not peak_at_end("u", {"time": time, "u": [0.0, 2.0, 1.0]})
    assert not peak_at_end("u", {"time": time, "u": [0.0, 0.0, 0.0]})  # nothing moved: no peak to miss


def test_interface_patch_without_strain_is_refused(femdem):
    # was exit 3 ("not finite; likely cause: check the time step") and three raw RuntimeWarnings
    code, summary, err = femdem("run", "interface_patch", "--set", "strain.xx=0", "--set", "strain.xy=0",
                                "--set", "strain.yy=0")
    _one_line_refusal(code, summary, err, "strain.xx = 0", "nothing to test", "allowed:")
