"""Hard cases (issue: robustness): each stays stable within its energy tolerance or stops
with exit code 3 and a diagnostic that names the cause."""
import pytest

from conftest import assert_checks


def test_stiffness_contrast_1000_synchronous_is_exact(femdem):
    """DEM bonds 1000 x stiffer than the FEM elements, m = 1: still the monolithic chain."""
    code, s, _ = femdem("run", "chain_consistency", "--set", "chain.stiffness_ratio=1000", "--set", "clock.substeps=1")
    assert code == 0
    assert_checks(s)
    assert s["energy"]["balance_error_rel"] < 1e-3


def test_stiffness_contrast_1000_subcycled(femdem):
    """m = 4 stays within 1 % of energy and 2 % of the fine monolithic chain; the automatic
    m = 31 lands on an impulse resonance and must stop with that diagnosis."""
    code, s, _ = femdem("run", "chain_consistency", "--set", "chain.stiffness_ratio=1000", "--set", "clock.substeps=4")
    assert code == 0 and s["energy"]["balance_error_rel"] < 0.01
    assert s["qoi"]["max_rel_diff_vs_monolithic"] < 0.02
    code, s, _ = femdem("run", "chain_consistency", "--set", "chain.stiffness_ratio=1000")
    assert code == 3 and s["clock"]["substeps"] == 31 and "resonates" in s["message"]


def test_subcycling_ratio_20(femdem):
    code, s, _ = femdem("run", "coupled_free_flight", "--set", "clock.substeps=20", "--set", "run.steps=200")
    assert code == 0 and s["clock"]["substeps"] == 20
    assert s["qoi"]["momentum_drift_rel"] < 1e-11 and s["energy"]["balance_error_rel"] < 0.01


def test_time_step_above_the_stable_limit_is_refused(femdem):
    code, s, err = femdem("run", "coupled_free_flight", "--set", "clock.dt=1e-3")
    assert code == 2 and s is None and "clock.dt" in err and "stable" in err


@pytest.mark.slow
def test_one_million_steps(femdem):
    code, s, _ = femdem("run", "free_vibration", "--set", "run.steps=1000000")
    assert code == 0 and s["clock"]["steps"] == 1_000_000
    assert_checks(s)
