"""Cusp points of the singular curve, against reference values for
rho1 = 17 (found independently of this code)."""

import json
import math

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, InvalidInputError, build_roadmap
from rpr3_gwr_core.io.cli import main
from rpr3_gwr_core.workspace import Grid
from rpr3_gwr_core.workspace.cusps import find_cusps

# (rho2, rho3) of the six cusps in [0, 50]^2 at rho1 = 17.
CUSPS_AT_17 = [(2.8348, 5.7898), (15.9226, 6.2851), (15.9630, 26.5963), (18.0409, 31.5964),
               (31.9522, 14.2655), (32.4043, 28.6145)]


@pytest.fixture(scope="module")
def cusps(paper_roadmap):
    return find_cusps(paper_roadmap)


def test_the_six_cusps_at_rho1_17(cusps):
    np.testing.assert_allclose([c.joints[1:] for c in cusps], CUSPS_AT_17, atol=1e-4)
    assert all(c.joints[0] == 17.0 and c.regions for c in cusps)


def test_cusps_are_singular_poses_with_their_legs(cusps):
    for cusp in cusps:
        np.testing.assert_allclose(PAPER_GEOMETRY.inverse(cusp.pose), cusp.joints, atol=1e-9)
        assert abs(PAPER_GEOMETRY.margin(cusp.pose)) < 1e-6


def test_the_first_cusp_lies_by_a_degenerate_orientation(cusps):
    gap = np.min(np.abs(PAPER_GEOMETRY.degenerate_orientations() - cusps[0].pose[2]))
    assert gap < 0.005


def test_cusps_are_points_of_two_axis_grids():
    grid = Grid.regular({0: (12.0, 14.0), 1: (10.0, 12.0), 2: (16.0, 18.0)}, 1.0)
    with pytest.raises(InvalidInputError):
        find_cusps(build_roadmap(PAPER_GEOMETRY, grid))


def test_the_cli_prints_the_cusps(tmp_path, capsys):
    assert main(["cusps", "--rho1", "17", "--cache-dir", str(tmp_path)]) == 0
    printed = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose([[c["rho2"], c["rho3"]] for c in printed], CUSPS_AT_17,
                               atol=1e-4)
    assert all(-180 < c["alpha_deg"] <= 180 and c["regions"] for c in printed)


def test_cusp_curves_run_through_the_cusps_of_every_slice(capsys):
    assert main(["cusps", "--trace", "15", "19", "1"]) == 0
    curves = json.loads(capsys.readouterr().out)["curves"]
    assert len(curves) == 6 and all(len(curve) == 5 for curve in curves)
    at_17 = sorted((c["rho2"], c["rho3"]) for curve in curves for c in curve if c["rho1"] == 17)
    np.testing.assert_allclose(at_17, CUSPS_AT_17, atol=1e-4)
    for curve in curves:
        legs = np.array([[c["rho1"], c["rho2"], c["rho3"]] for c in curve])
        # Each curve moves a little from one slice to the next: a curve, not a jump.
        assert np.all(np.linalg.norm(np.diff(legs, axis=0), axis=1) < 2.0)
        for c in curve:
            pose = np.array([c["x"], c["y"], math.radians(c["alpha_deg"])])
            assert abs(PAPER_GEOMETRY.margin(pose)) < 1e-6


def test_cusp_curves_need_slices_along_one_joint():
    from rpr3_gwr_core.paper import rho1_slice
    from rpr3_gwr_core.workspace.cusps import cusp_curves

    coarse = [build_roadmap(PAPER_GEOMETRY, rho1_slice(v, step=1.0)) for v in (18.0, 17.0)]
    with pytest.raises(InvalidInputError):
        cusp_curves(coarse)
