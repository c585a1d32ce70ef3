"""The seed paper's examples (issue 9): coarse variants with their checks, and the coupled
model against its standalone references when nothing breaks."""
import pytest

from conftest import assert_checks

# every strength and toughness out of reach: the same beam, elastic
ELASTIC = [f"--set={k}=1e11" for k in ("strength.Xt", "strength.Xc", "strength.Yt", "strength.Yc", "strength.S12",
                                         "strength.S23")] + \
          ["--set=interface.Z0=1e10", "--set=interface.R0=1e10", "--set=interface.GIc=1e7", "--set=interface.GIIc=1e7"]


def test_beam_impact_coarse(femdem, tmp_path):
    code, s, err = femdem("run", "beam_impact_coarse")
    assert code == 0, err
    assert_checks(s)
    q = s["qoi"]
    assert {"peak_contact_force", "delamination_length_0", "delamination_length_1", "matrix_cracks"} <= set(q)
    assert q["model_size_vs_reference"] < 0.05
    assert 0.0 <= q["damage_at_zone_edge"] <= 1.0
    assert q["damaged_interface_length_0"] > 0 and q["damaged_interface_length_1"] > 0  # both 0/90 interfaces


def test_beam_impact_coupled_equals_fem_when_elastic(femdem):
    """With damage out of reach the coupled model (DEM zone + FEM) and the all-FEM beam give
    the same peak centre deflection within 3 %: the zone and the tie add no spurious compliance."""
    peaks = {}
    for mode in ("fem", "coupled"):
        code, s, err = femdem("run", "beam_impact_coarse", "--mode", mode, *ELASTIC)
        assert code == 0, err
        peaks[mode] = s["qoi"]["peak_centre_displacement"]
    assert abs(peaks["coupled"] / peaks["fem"] - 1) < 0.03


@pytest.mark.slow
def test_beam_impact_all_dem_equals_fem_when_elastic(femdem):
    """The all-particle reference (the lattice alone) against the all-FEM beam: within 5 %."""
    peaks = {}
    for mode in ("fem", "dem"):
        code, s, err = femdem("run", "beam_impact_coarse", "--mode", mode, *ELASTIC)
        assert code == 0, err
        peaks[mode] = s["qoi"]["peak_centre_displacement"]
    assert abs(peaks["dem"] / peaks["fem"] - 1) < 0.05
