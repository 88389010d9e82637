"""What every mechanism of the mechanism files (``config/*.yaml``) owes the
:class:`~rpr3_gwr_core.mechanisms.base.Mechanism` interface: its names and
geometry (the expected values written again rather than read from the
mechanism), its plain-data round trip, the refusal of malformed geometry and
joints, a margin that asks for the joints where the pose alone does not fix
it, and a compiled step (:attr:`Mechanism.step_kernel`, as the compiled
loops call it) that is :meth:`Mechanism.step`.  The mechanisms whose base
points move with their joints (the 3-RRR and the 3-PRR) are held to the
same independent reference (``moving_base_reference.py``, each mechanism's
written in its test file): residual and margin, direct kinematics through
the torus of poses at a fixed first joint, and continuation.

Each mechanism's other checks against its own references are in its test
file."""

from dataclasses import dataclass, field, replace
import json
import math
import pathlib

import numba
import numpy as np
import pytest

from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.mechanisms import Mechanism, mechanism_from_dict

import test_prr3
import test_rrr3

CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"

# The paper's base points and platform (sides 17.04, 16.54, 20.84), which
# the 3-RPR, the 3-RRR and the 3-PRR share.
A1, A2, A3 = (0.0, 0.0), (15.91, 0.0), (0.0, 10.0)
D1, D2, D3 = 17.04, 16.54, 20.84
BETA = math.acos((D1**2 + D3**2 - D2**2) / (2 * D1 * D3))
PLATFORM = {"a1": A1, "a2": A2, "a3": A3, "d1": D1, "d3": D3}
# The five-bar's proportions [m].
D, L1, L2 = 0.118, 0.09, 0.118

# A key of a malformed document's change that takes the key out.
MISSING = object()


@dataclass(frozen=True)
class Case:
    """What one mechanism file's mechanism is expected to be."""

    kind: str
    joint_names: tuple
    pose_names: tuple
    angular: tuple
    mode_coordinate: int
    max_solutions: int
    scale: float
    # Fields compared exactly, then beta (if any) to 1e-12.
    fields: dict
    beta: float = None
    # Fields that make another geometry of the kind, for the round trip.
    other: dict = field(default_factory=dict)
    # Changes to the default document that must be refused.
    malformed: tuple = ()
    malformed_joints: tuple = ()
    # Whether the margin of a pose needs its joints.
    margin_needs_joints: bool = True
    # Joints with solutions, where a step to joints + move succeeds.
    joints: tuple = ()
    move: float = 0.01
    n_parameters: int = 0
    # The step kernel's parameters where they are written again here.
    parameters: tuple = None
    # How far the compiled step may be from step (0: to the bit).
    kernel_tol: float = 1e-13


THREE_JOINT_MALFORMED = ([0.0, 1.0], [0.0, math.nan, 1.0], "abc")

CASES = {
    "paper_3rpr.yaml": Case(
        kind="3-RPR", joint_names=("rho1", "rho2", "rho3"), pose_names=("x", "y", "alpha"),
        angular=(False, False, True), mode_coordinate=2, max_solutions=6, scale=D3,
        fields=PLATFORM, beta=BETA, other={"a2": (16.0, 1.0), "d1": 16.5},
        malformed=({"a1": (0.0,)}, {"beta": 0.0}, {"d1": math.inf}, {"d1": -1.0},
                   {"d3": "20"}, {"a2": (math.nan, 0.0)}, {"d3": MISSING}),
        malformed_joints=THREE_JOINT_MALFORMED + ([1.0, -2.0, 3.0],),
        margin_needs_joints=False, joints=(17.0, 12.0, 18.0), n_parameters=10,
        parameters=(*A1, *A2, *A3, D1, D3, BETA, D3)),
    "five_bar.yaml": Case(
        kind="5R", joint_names=("th1", "th2"), pose_names=("x", "y"), angular=(False, False),
        mode_coordinate=1, max_solutions=2, scale=L1 + L2,
        fields={"d": D, "l1": L1, "l2": L2}, other={"d": 0.2, "l1": 0.15, "l2": 0.25},
        malformed=({"d": 0.1, "l1": 0.1, "l2": MISSING},
                   {"d": 0.1, "l1": 0.1, "l2": "long"},
                   {"d": 0.1, "l1": -0.1, "l2": 0.1},
                   {"d": 0.0, "l1": 0.1, "l2": 0.1},
                   {"d": math.inf, "l1": 0.1, "l2": 0.1},
                   {"d": math.nan, "l1": 0.1, "l2": 0.1},
                   {"d": True, "l1": 0.1, "l2": 0.1}),
        malformed_joints=([0.0], [math.nan, 0.0], "abc"),
        joints=(2.0, 1.1), n_parameters=4, parameters=(D, L1, L2, L1 + L2), kernel_tol=0.0),
    "three_rrr.yaml": Case(
        kind="3-RRR", joint_names=("th1", "th2", "th3"), pose_names=("x", "y", "alpha"),
        angular=(False, False, True), mode_coordinate=2, max_solutions=6, scale=D3,
        fields={**PLATFORM, "l1": 8.0, "l2": 12.0}, beta=BETA,
        other={"a2": (16.0, 1.0), "l1": 7.5, "l2": 11.0},
        malformed=({"l1": 0.0}, {"l2": -1.0}, {"l1": math.nan}, {"l2": "12"}, {"l1": True},
                   {"a1": (0.0,)}, {"beta": 0.0}, {"d1": math.inf}),
        malformed_joints=THREE_JOINT_MALFORMED, joints=(0.0, 0.13499, 0.55223),
        n_parameters=19),
    "three_prr.yaml": Case(
        kind="3-PRR", joint_names=("s1", "s2", "s3"), pose_names=("x", "y", "alpha"),
        angular=(False, False, True), mode_coordinate=2, max_solutions=6, scale=D3,
        fields={**PLATFORM, "gamma1": 0.0, "gamma2": math.pi / 2, "gamma3": math.pi / 4,
                "l": 15.0},
        beta=BETA, other={"a2": (16.0, 1.0), "gamma1": 0.3, "gamma3": -2.0, "l": 13.5},
        malformed=({"l": 0.0}, {"l": -1.0}, {"l": math.nan}, {"l": "12"}, {"l": True},
                   {"gamma1": math.inf}, {"gamma2": "0"}, {"gamma3": None}, {"a1": (0.0,)},
                   {"beta": 0.0}, {"d1": math.inf}, {"gamma2": MISSING}),
        malformed_joints=THREE_JOINT_MALFORMED, joints=(5.0, 26.5, 10.0), move=0.05,
        n_parameters=19),
}


def test_every_mechanism_file_has_a_case():
    assert sorted(p.name for p in CONFIG.glob("*.yaml")) == sorted(CASES)


def _mechanism(name):
    return load_mechanism_file(CONFIG / name).mechanism


def _changed(document, change):
    document = {**document, **change}
    return {key: value for key, value in document.items() if value is not MISSING}


@numba.njit
def _compiled_step(kernel, parameters, pose, joints_from, joints_to):
    return kernel(parameters, pose, joints_from, joints_to)


@pytest.mark.parametrize("name", CASES)
def test_names_and_geometry(name):
    m, case = _mechanism(name), CASES[name]
    assert isinstance(m, Mechanism) and m.kind == case.kind
    assert m.joint_names == case.joint_names and m.pose_names == case.pose_names
    assert m.angular == case.angular and m.mode_coordinate == case.mode_coordinate
    assert m.max_solutions == case.max_solutions
    assert (m.n_joints, m.pose_size) == (len(case.joint_names), len(case.pose_names))
    for key, value in case.fields.items():
        assert np.array_equal(getattr(m, key), value), key
    if case.beta is not None:
        assert m.beta == pytest.approx(case.beta, abs=1e-12)
    assert m.scale == pytest.approx(case.scale)


@pytest.mark.parametrize("name", CASES)
def test_to_dict_round_trip(name):
    default, case = _mechanism(name), CASES[name]
    m = replace(default, **case.other)
    assert m != default
    data = json.loads(json.dumps(m.to_dict()))
    assert data["kind"] == case.kind
    back = mechanism_from_dict(data)
    assert isinstance(back, type(m)) and back == m and back.to_dict() == m.to_dict()
    assert mechanism_from_dict(default.to_dict()) == default


@pytest.mark.parametrize("name, change", [(name, change) for name, case in CASES.items()
                                          for change in case.malformed])
def test_malformed_geometry_is_refused(name, change):
    data = _changed(_mechanism(name).to_dict(), change)
    with pytest.raises(InvalidInputError):
        mechanism_from_dict(data)


@pytest.mark.parametrize("name, joints", [(name, joints) for name, case in CASES.items()
                                          for joints in case.malformed_joints])
def test_malformed_joints_are_refused(name, joints):
    with pytest.raises(InvalidInputError):
        _mechanism(name).check_joints(joints)


@pytest.mark.parametrize("name", [name for name, case in CASES.items()
                                  if case.margin_needs_joints])
def test_margin_needs_the_joints(name):
    m, joints = _mechanism(name), np.array(CASES[name].joints)
    count, poses = m.solve(joints[None])
    assert count[0] > 0
    with pytest.raises(TypeError, match="needs the joints"):
        m.margin(poses[0, 0])
    one = m.margin(poses[0, 0], joints)
    assert np.ndim(one) == 0
    assert one == m.margin(poses[0, : count[0]], joints)[0]


@pytest.mark.parametrize("name", CASES)
def test_compiled_step_kernel_agrees_with_step(name):
    m, case = _mechanism(name), CASES[name]
    kernel, parameters = m.step_kernel
    assert kernel is not None and parameters.shape == (case.n_parameters,)
    if case.parameters is not None:
        assert parameters.tolist() == list(case.parameters)
    joints = np.array(case.joints)
    target = joints + case.move
    count, poses = m.solve(joints[None])
    assert count[0] > 0
    for pose in poses[0, : count[0]]:
        expected = m.step(pose, joints, target)
        assert expected is not None
        buffer = pose.copy()
        margin = _compiled_step(kernel, parameters, buffer, joints, target)
        if case.kernel_tol:
            assert np.allclose(buffer, expected[0], rtol=0, atol=case.kernel_tol)
            assert margin == pytest.approx(expected[1], abs=case.kernel_tol)
        else:
            assert margin == expected[1] and tuple(buffer) == tuple(expected[0])


# --- the mechanisms whose base points move with their joints ----------------------

@dataclass(frozen=True)
class MovingBaseCase:
    """A moving-base mechanism's reference and where it is checked."""

    # Its MovingBaseReference.
    reference: object
    # Joints, and how many solutions they have, found on the torus by a
    # scan of +- window around the first joint's line.
    preimages: tuple
    window: float
    # The first joint of the dense torus sample.
    first_joint: float
    # Random poses up to (high, high, pi) and joints in this range.
    pose_high: float
    joint_range: tuple
    residual_atol: float
    # Joints of the dense count check, and whether all of 0, 2, 4, 6 occur.
    dense_range: tuple
    every_count: bool
    # Joints whose every solution a walk of this step follows.
    walked: tuple
    step: float


MOVING_BASE = {
    "three_rrr.yaml": MovingBaseCase(
        reference=test_rrr3.REFERENCE,
        preimages=((test_rrr3.Q6, 6), ((0.0, 0.0, 0.0), 6), ((0.0, 1.0, 2.0), 4),
                   ((0.0, -1.0, 0.5), 2), ((0.0, 2.5, -2.0), 2), ((0.3, -2.0, 1.0), 2)),
        window=0.5, first_joint=0.0, pose_high=20.0, joint_range=(-math.pi, math.pi),
        residual_atol=1e-10, dense_range=(-math.pi, math.pi), every_count=True,
        walked=test_rrr3.Q6, step=0.002),
    "three_prr.yaml": MovingBaseCase(
        reference=test_prr3.REFERENCE,
        preimages=((test_prr3.Q_CHANGE, 4), ((5.0, 16.49, 0.83), 6), ((5.0, 9.89, 23.65), 6),
                   ((5.0, 9.35, 12.7), 2), ((5.0, 24.83, 12.28), 4), ((5.0, 6.1, 7.87), 2)),
        window=2.0, first_joint=test_prr3.S1, pose_high=30.0, joint_range=(-5.0, 35.0),
        residual_atol=1e-9, dense_range=(-10.0, 40.0), every_count=False,
        walked=(5.0, 16.49, 0.83), step=0.01),
}


@pytest.mark.parametrize("name", MOVING_BASE)
def test_margin_and_residual_are_the_reference(name):
    m, case = _mechanism(name), MOVING_BASE[name]
    reference = case.reference
    rng = np.random.default_rng(2)
    poses = rng.uniform([-10, -10, -math.pi], [case.pose_high, case.pose_high, math.pi],
                        (500, 3))
    joints = rng.uniform(*case.joint_range, (500, 3))
    assert np.allclose(m.residual(poses, joints), reference.residual(poses, joints),
                       rtol=0, atol=case.residual_atol)
    assert np.allclose(m.margin(poses, joints), reference.margin(poses, joints),
                       rtol=0, atol=1e-12)
    assert np.all(m.aspect(poses, joints) == np.sign(reference.margin(poses, joints)))
    one = m.margin(poses[0], joints[0])
    assert np.ndim(one) == 0 and one == pytest.approx(reference.margin(poses[0], joints[0]))


@pytest.mark.parametrize("name, joints, n_solutions",
                         [(name, joints, n) for name, case in MOVING_BASE.items()
                          for joints, n in case.preimages])
def test_solutions_are_the_torus_preimages(name, joints, n_solutions):
    m, case = _mechanism(name), MOVING_BASE[name]
    reference = case.reference
    expected = reference.torus_preimages(joints, window=case.window)
    count, poses = m.solve(np.array([joints]))
    assert len(expected) == n_solutions == count[0]
    assert np.max(np.abs(poses[0, :n_solutions] - expected)) < 1e-8
    assert np.all(np.isnan(poses[0, n_solutions:]))
    assert np.max(np.abs(reference.residual(expected, joints))) < 1e-8
    # All are regular: no two solutions merge at these joints.
    assert np.min(np.abs(reference.margin(expected, joints))) > 0.1


@pytest.mark.parametrize("name", MOVING_BASE)
def test_torus_points_are_found_and_every_solution_fits(name):
    """Joints made from a dense torus sample at a fixed first joint: each
    has the pose it was made from among its solutions, and every solution
    fits the legs."""
    case = MOVING_BASE[name]
    seen = case.reference.check_torus_points(_mechanism(name), case.first_joint)
    assert seen[0] == 0 and seen[2] and seen[4] and seen[6]


@pytest.mark.parametrize("name", MOVING_BASE)
def test_never_more_than_six_and_counts_are_even(name):
    m, case = _mechanism(name), MOVING_BASE[name]
    rng = np.random.default_rng(5)
    joints = rng.uniform(*case.dense_range, (20000, 3))
    count, poses = m.solve(joints)
    assert count.dtype == np.uint8 and poses.shape == (20000, 6, 3)
    counts = set(np.unique(count).tolist())
    assert counts == {0, 2, 4, 6} if case.every_count else counts <= {0, 2, 4, 6}
    finite = np.isfinite(poses[..., 0])
    assert np.array_equal(finite.sum(1), count)
    misfit = np.nanmax(np.abs(case.reference.residual(poses, joints[:, None, :])))
    assert misfit < 1e-9 * m.scale**2


@pytest.mark.parametrize("name", MOVING_BASE)
def test_step_follows_each_solution(name):
    case = MOVING_BASE[name]
    case.reference.check_step_follows_each_solution(_mechanism(name), case.walked, case.step)
