"""The same code path on a grid of three axes: all three legs of the 3-RPR
sampled (11 x 11 x 11 cells), no rho1 fixed."""

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, Grid, Planner, aspect_groups, build_roadmap
from rpr3_gwr_core.planning import validate_path
from rpr3_gwr_core.workspace import segment

GRID_3D = Grid.regular({0: (12.0, 22.0), 1: (10.0, 20.0), 2: (16.0, 26.0)}, 1.0)


@pytest.fixture(scope="module")
def roadmap_3d():
    return build_roadmap(PAPER_GEOMETRY, GRID_3D)


def test_a_three_axis_grid_has_regions_patches_and_gates(roadmap_3d):
    seg = roadmap_3d.segmentation
    assert GRID_3D.shape == (11, 11, 11) and not GRID_3D.fixed
    assert seg.n_regions > 1 and len(seg.patches) > seg.n_regions and seg.gates
    assert len(seg.links) == 3
    for patch in seg.patches.values():
        assert np.all(np.sign(seg.field.margin[patch.cells, patch.slots]) == patch.aspect)
    for a, b in seg.gates:
        assert seg.patches[a].aspect == seg.patches[b].aspect
    assert all(len({seg.patches[p].aspect for p in group}) == 1
               for group in aspect_groups(roadmap_3d.graph))


def test_the_rotary_disk_search_in_three_dimensions_finds_the_same_patches(roadmap_3d):
    rds = segment(roadmap_3d.field, method="rds")
    np.testing.assert_array_equal(rds.patch, roadmap_3d.segmentation.patch)


def test_a_plan_on_the_three_axis_grid_moves_all_legs_and_validates(roadmap_3d):
    seg, grid = roadmap_3d.segmentation, roadmap_3d.grid
    patch = max(seg.patches.values(), key=lambda p: p.cells.size)
    legs = grid.joints()[patch.cells]
    # The goal differs from the start in every leg, as much as the patch allows.
    far = int(np.argmax(np.min(np.abs(legs - legs[0]), axis=1)))
    ends = [(*legs[k], float(seg.field.poses[patch.cells[k], patch.slots[k], 2]))
            for k in (0, far)]
    plan = Planner(roadmap_3d).plan(*ends)
    assert np.all(np.ptp(plan.joints, axis=0) > 0), "some leg did not move"
    check = validate_path(PAPER_GEOMETRY, plan.joints, plan.start.pose, plan.goal.pose)
    assert check.ok, check.reason
