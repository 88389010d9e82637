"""Malformed input raises the package's own errors."""

import math
import pickle

import numpy as np
import pytest

from rpr3_gwr_core.exceptions import (INFEASIBLE_REASONS, GWRError, InfeasiblePathError,
                                      InvalidInputError, OutOfGridError, UndecidedError)
from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.workspace import compute_field
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY, ThreeRPR, beta_from_sides
from rpr3_gwr_core.workspace.rotary_disk import rotary_order
from rpr3_gwr_core.workspace.segmentation import segment

NAN, INF = math.nan, math.inf


def test_invalid_input_error_is_a_gwr_error_and_a_value_error():
    assert issubclass(InvalidInputError, GWRError)
    assert issubclass(InvalidInputError, ValueError)
    assert issubclass(OutOfGridError, GWRError)


@pytest.mark.parametrize("reason", [*INFEASIBLE_REASONS, None])
def test_an_infeasible_path_keeps_its_reason_across_processes(reason):
    # The plan workers send their errors to the node through a pipe.
    error = pickle.loads(pickle.dumps(InfeasiblePathError("no path", reason)))
    assert (type(error), str(error), error.reason) == (InfeasiblePathError, "no path", reason)


def test_an_undecided_answer_keeps_where_and_at_which_size_across_processes():
    error = pickle.loads(pickle.dumps(UndecidedError("undecided", [113, 120], [0.0625, 0.25])))
    assert (type(error), str(error), error.thin_patches, error.steps) == (
        UndecidedError, "undecided", (113, 120), (0.0625, 0.25))
    assert not isinstance(error, InfeasiblePathError)


def test_an_infeasible_path_refuses_a_reason_callers_cannot_map():
    with pytest.raises(ValueError, match="other_aspect"):
        InfeasiblePathError("no path", "far away")


@pytest.mark.parametrize("pose", [[NAN, 1.0, 0.0], [1.0, INF, 0.0], [1.0, 2.0, -INF],
                                  [1.0, 2.0], [1.0, 2.0, 3.0, 4.0], [[1.0, 2.0], [3.0, 4.0]]])
@pytest.mark.parametrize("method", ["inverse", "passive_angles", "parallel_jacobian"])
def test_pose_methods_reject_bad_poses(pose, method):
    with pytest.raises(InvalidInputError):
        getattr(PAPER_GEOMETRY, method)(np.array(pose))


@pytest.mark.parametrize("rho", [[NAN, 12.0, 18.0], [17.0, INF, 18.0], [17.0, 12.0, -18.0],
                                 [17.0, 12.0], [17.0, 12.0, 18.0, 1.0], [[17.0, 12.0, 18.0]]])
def test_direct_kinematics_rejects_bad_legs(rho):
    with pytest.raises(InvalidInputError):
        PAPER_GEOMETRY.direct_kinematics(np.array(rho))


@pytest.mark.parametrize("rho", [[17.0, 12.0, 18.0], [[[17.0, 12.0, 18.0]]], [[-1.0, 2.0, 3.0]]])
def test_solve_rejects_bad_shapes_and_values(rho):
    with pytest.raises(InvalidInputError):
        PAPER_GEOMETRY.solve(np.array(rho))


@pytest.mark.parametrize("kwargs", [
    {"rho1": NAN}, {"rho1": INF}, {"rho1": -1.0}, {"rho1": 0.0},
    {"step": 0.0}, {"step": -0.125}, {"step": NAN},
    {"rho2_range": (-1.0, 5.0)}, {"rho3_range": (5.0, 1.0)}, {"rho2_range": (0.0, INF)},
    {"rho2_range": (0.0,)}, {"rho3_range": (0.0, 1.0, 2.0)}, {"rho1": "17"},
])
def test_grid_rejects_bad_values(kwargs):
    with pytest.raises(InvalidInputError):
        rho1_slice(**kwargs)


@pytest.mark.parametrize("kwargs", [
    {"a2": (NAN, 0.0)}, {"a3": (0.0, INF)}, {"a1": (0.0, 0.0, 0.0)}, {"a1": (1.0,)},
    {"d1": -1.0}, {"d3": 0.0}, {"d1": NAN}, {"beta": INF}, {"beta": 0.0},
])
def test_geometry_rejects_bad_values(kwargs):
    with pytest.raises(InvalidInputError):
        ThreeRPR(**kwargs)


def test_geometry_rejects_a_flat_platform_at_pi():
    with pytest.raises(InvalidInputError):
        ThreeRPR(beta=math.pi)


def test_geometry_rejects_a_scalar_base_point():
    with pytest.raises(InvalidInputError):
        ThreeRPR(a2=5.0)


@pytest.mark.parametrize("sides", [(1.0, 5.0, 1.0), (0.0, 1.0, 1.0), (NAN, 1.0, 1.0),
                                   (1.0, 2.0, 1.0)])
def test_beta_from_sides_rejects_non_triangles(sides):
    with pytest.raises(InvalidInputError):
        beta_from_sides(*sides)


@pytest.mark.parametrize("point", [(-0.3, 10.0), (10.0, -0.3), (50.3, 10.0), (10.0, 60.0)])
def test_cell_of_outside_the_grid_raises_out_of_grid(point):
    with pytest.raises(OutOfGridError):
        rho1_slice(step=0.5).cell_of((17.0, *point))


@pytest.mark.parametrize("point", [(NAN, 10.0), (10.0, INF)])
def test_cell_of_non_finite_raises_a_gwr_error(point):
    with pytest.raises(GWRError):
        rho1_slice(step=0.5).cell_of((17.0, *point))


def _tiny_field():
    grid = rho1_slice(rho2_range=(10.0, 12.0), rho3_range=(20.0, 22.0), step=1.0)
    return compute_field(PAPER_GEOMETRY, grid)


def test_segment_rejects_an_unknown_method():
    with pytest.raises(InvalidInputError):
        segment(_tiny_field(), method="bogus")


def test_segment_rejects_min_region_cells_below_one():
    with pytest.raises(InvalidInputError):
        segment(_tiny_field(), min_region_cells=0)


def test_rotary_order_rejects_dimension_zero():
    with pytest.raises(InvalidInputError):
        rotary_order(0)
