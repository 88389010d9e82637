"""Every mechanism's compiled predictor (:attr:`Mechanism.predict_kernel`),
which continuity's screen calls, against its batch :meth:`Mechanism.predict`
and against the solutions of the moved joints themselves: an Euler step is
exact to first order, so its error is far below the move."""

import pathlib

import numba
import numpy as np
import pytest

from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.workspace.continuity import _screened, match_solutions
from rpr3_gwr_core.workspace.field import compute_field

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"
# Each mechanism file and the joint its slice fixes (on the file's grid).
SLICES = {"paper_3rpr.yaml": {"rho1": 17.0}, "five_bar.yaml": {},
          "three_rrr.yaml": {"th1": 0.0}, "three_prr.yaml": {"s1": 5.0}}


@numba.njit
def _predict(kernel, parameters, poses, joints_from, joints_to):
    out = np.empty_like(poses)
    kernel(parameters, poses, joints_from, joints_to, out)
    return out


def _described(name):
    return load_mechanism_file(CONFIG / name)


@pytest.mark.parametrize("name", SLICES)
def test_the_compiled_predictor_is_the_batch_predictor_to_first_order_exact(name):
    mechanism = _described(name).mechanism
    kernel, parameters = mechanism.predict_kernel
    rng = np.random.default_rng(7)
    box = _described(name).axes
    low, high = np.array([a.low for a in box]), np.array([a.high for a in box])
    checked = 0
    for joints in rng.uniform(low, high, (400, mechanism.n_joints)):
        count, poses = mechanism.solve(joints[None])
        poses = np.ascontiguousarray(poses[0, :count[0]])
        margin = mechanism.margin(poses, joints)
        poses = poses[np.abs(margin) > 0.1]
        if poses.size == 0:
            continue
        # A step of a millionth of the box moves the platform to first order.
        moved = joints + rng.normal(size=joints.size) * 1e-6 * (high - low)
        predicted = _predict(kernel, parameters, poses, joints, moved)
        np.testing.assert_allclose(predicted, mechanism.predict(poses, joints, moved),
                                   rtol=0, atol=1e-12 * mechanism.scale)
        count, exact = mechanism.solve(moved[None])
        for pose, guess in zip(poses, predicted):
            error = mechanism.pose_distance(exact[0, :count[0]], guess).min()
            move = mechanism.pose_distance(pose, guess)
            assert error < 1e-3 * move
            checked += 1
    assert checked > 100


@pytest.mark.parametrize("name", SLICES)
def test_the_screen_settles_most_faces_and_leaves_the_links_unchanged(name):
    described = _described(name)
    grid = described.grid(SLICES[name])
    field = compute_field(described.mechanism, grid)
    joints = grid.joints()
    for axis, (lower, upper) in enumerate(grid.pairs()):
        settled = _screened(field, joints, lower, upper)
        both = (field.count[lower] > 0) & (field.count[upper] > 0)
        assert settled[both].mean() > 0.8
        tracked = match_solutions(field, lower, upper, screen=False)
        np.testing.assert_array_equal(match_solutions(field, lower, upper), tracked)
        # A settled face's links are the identity on the ordered solutions.
        identity = np.where(field.valid[lower], np.arange(field.max_solutions), -1)
        np.testing.assert_array_equal(tracked[settled], identity[settled])
        if grid.axes[axis].periodic:
            # The faces across the seam are the last of the axis's pairs: a
            # prediction there must move a step, not a turn back.
            seam = np.zeros(lower.size, dtype=bool)
            seam[-grid.size // grid.shape[axis]:] = True
            assert settled[seam & both].mean() > 0.8
