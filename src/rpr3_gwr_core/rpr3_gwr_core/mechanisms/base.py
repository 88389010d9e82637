"""The mechanism interface: everything the roadmap, the planner and the
validator know of a parallel mechanism.

A mechanism relates its actuated joints ``q`` (shape ``(n_joints,)``) and its
platform pose ``x`` (shape ``(pose_size,)``) by constraint equations
``F(q, x) = 0``; the direct kinematics has at most ``max_solutions`` poses per
``q``.  Like OMPL's state space, it is an object of its own, separate from
the roadmap built over its joints and from the planner that uses both.

Vectorised methods take arrays with any leading shape; :meth:`Mechanism.step`
is the scalar predictor-corrector step that sequential continuation (the
validator, the driver) takes thousands of times, so implementations serve it
from the same equations evaluated on floats.  A mechanism may also offer that
step compiled (:attr:`Mechanism.step_kernel`), so the validator's whole loop
runs outside the interpreter; every mechanism offers its predictor compiled
(:attr:`Mechanism.predict_kernel`), so continuity screens the faces of a grid
in one compiled loop.
"""

import abc
import dataclasses
import itertools
import math
import numbers

import numba
from numba import types
from numba.core.types.function_type import CompileResultWAP
import numpy as np

from ..exceptions import InvalidInputError
from .continuation import STEP_KERNEL_SIGNATURE

__all__ = ["Mechanism", "mechanism_class", "mechanism_from_dict", "register_mechanism",
           "STEP_KERNEL_SIGNATURE", "PREDICT_KERNEL_SIGNATURE", "first_class",
           "positive_length", "finite_vectors", "working_mode_label", "revolute_leg_angles",
           "compiled_pose_distance"]

# A leg's reach compared with rounding: a point at exactly a leg's full
# stretch (or fold) computes a cosine beyond 1 by a few ulps, and is reached.
_REACH_ROUNDING = 1e-12

# ``kernel(parameters, poses, joints_from, joints_to, out)``: the Euler
# predictor of :meth:`Mechanism.predict` for the rows of ``poses`` (k,
# pose_size), solutions of ``joints_from``, moved to ``joints_to``, written
# to the rows of ``out`` (k, pose_size).
PREDICT_KERNEL_SIGNATURE = types.void(types.float64[::1], types.float64[:, ::1],
                                      types.float64[::1], types.float64[::1],
                                      types.float64[:, ::1])

_REGISTRY = {}


def register_mechanism(kind):
    """Class decorator: make ``mechanism_from_dict`` rebuild ``kind`` documents."""
    def register(cls):
        _REGISTRY[kind] = cls
        cls.kind = kind
        return cls
    return register


def mechanism_class(kind):
    """The registered class of a mechanism kind.

    Raises
    ------
    InvalidInputError
        If the kind is unknown.
    """
    if not isinstance(kind, str) or kind not in _REGISTRY:
        raise InvalidInputError(f"unknown mechanism kind {kind!r}; known: {sorted(_REGISTRY)}")
    return _REGISTRY[kind]


def mechanism_from_dict(data):
    """Rebuild a mechanism from :meth:`Mechanism.to_dict`'s plain data.

    Raises
    ------
    InvalidInputError
        If the kind is unknown or its parameters malformed.
    """
    kind = data.get("kind") if isinstance(data, dict) else None
    return mechanism_class(kind).from_dict(data)


def first_class(dispatcher, signature):
    """A numba function compiled for ``signature`` (now, unless it was) as a
    first-class function that compiled loops take as an argument
    (:attr:`Mechanism.step_kernel`, :attr:`Mechanism.predict_kernel`)."""
    # Compiled (or loaded from numba's cache) on first use rather than at
    # import, which every fresh process pays.
    if signature.args not in dispatcher.overloads:
        dispatcher.compile(signature)
    # Its address taken once: passing the dispatcher itself would look it up,
    # under numba's compiler lock, at every call.
    compiled = CompileResultWAP(dispatcher.overloads[signature.args])
    # Typed once: numba would otherwise infer its type at every call.
    compiled._numba_type_ = types.FunctionType(signature)
    return compiled


def positive_length(value, name):
    """``float(value)`` for finite positive real numbers only (no strings),
    else ``InvalidInputError``: a mechanism's lengths."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise InvalidInputError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise InvalidInputError(f"{name} must be finite and positive, got {value}")
    return value


def finite_vectors(values, what, size):
    """Finite float array of shape (..., size), else ``InvalidInputError``:
    a batch of joints or poses."""
    try:
        values = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInputError(f"{what} must be numbers, got {values!r}") from None
    if values.shape[-1:] != (size,):
        raise InvalidInputError(f"{what} have {size} components, got shape {values.shape}")
    if not np.all(np.isfinite(values)):
        raise InvalidInputError(f"{what} contain NaN or infinity")
    return values


def working_mode_label(signs):
    """A working mode's branch signs as text, one character a leg: ``(+1, -1,
    +1)`` is ``"+-+"``."""
    return "".join("+" if sign > 0 else "-" for sign in signs)


def revolute_leg_angles(base, point, proximal, distal):
    """The actuated angles of an RR leg: a proximal link turning about
    ``base`` to an elbow ``C``, a distal link from ``C`` to ``point``.

    Parameters
    ----------
    base, point : ndarray, shape (..., 2)
        The turning joint A and the distal link's far end B [length unit],
        broadcast together.
    proximal, distal : float
        The links' lengths |AC| and |CB| [length unit].

    Returns
    -------
    ndarray, shape (..., 2)
        The angle of AC [rad] in (-pi, pi] on each branch: first the one
        whose elbow angle (the direction of CB relative to AC) lies in
        ``[0, pi]``, ``cross(C - A, B - C) >= 0`` (sign +1), then the other
        (sign -1); NaN on both where ``|AB|`` is beyond the links' reach (or
        0, where every angle or none is a solution).
    """
    reach = np.asarray(point, dtype=float) - np.asarray(base, dtype=float)
    length = np.hypot(reach[..., 0], reach[..., 1])
    # A length of 0, or so small that the quotient overflows, gives an
    # infinite or NaN cosine: not reached.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        cosine = (proximal * proximal + length * length - distal * distal) / (
            2.0 * proximal * length)
    reached = np.abs(cosine) <= 1.0 + _REACH_ROUNDING
    # The elbow lies at the angle psi from AB, on the side the sign names:
    # cross(C - A, B - C) = |AC| |AB| sin(phi - theta).
    psi = np.arccos(np.clip(np.where(reached, cosine, 0.0), -1.0, 1.0))
    phi = np.arctan2(reach[..., 1], reach[..., 0])
    angles = np.stack([phi - psi, phi + psi], axis=-1)
    angles = np.arctan2(np.sin(angles), np.cos(angles))
    return np.where(reached[..., None], angles, np.nan)


class Mechanism(abc.ABC):
    """A parallel mechanism: joints, poses and the equations between them.

    Attributes
    ----------
    kind : str
        Name of the mechanism in documents and messages.
    joint_names : tuple of str
        One per actuated joint.
    pose_names : tuple of str
        One per pose coordinate.
    angular : tuple of bool
        Which pose coordinates are angles [rad], compared modulo 2 pi.
    mode_coordinate : int
        The pose coordinate a request gives, beside the joints, to choose an
        assembly mode (the nearest solution in it is taken).
    leg_branches : int
        Joint values of one leg at one pose: 1 where a pose fixes each
        joint (the 3-RPR's legs), 2 where each leg has two branches (an
        elbow or a slider on either side); the inverse kinematics has
        ``leg_branches ** n_joints`` working modes.
    max_solutions : int
        Most direct-kinematic solutions of one joint vector.
    scale : float
        Length that makes angles commensurable with positions [length unit].
    angle_parameters : tuple of str
        The parameters of :meth:`to_dict` that are angles [rad].
    """

    kind = "abstract"
    joint_names = ()
    pose_names = ()
    angular = ()
    mode_coordinate = 0
    leg_branches = 1
    max_solutions = 0
    angle_parameters = ()

    @classmethod
    def parameter_names(cls):
        """The parameters of :meth:`to_dict` beside ``kind``, in order: a
        dataclass mechanism's fields (another kind overrides this)."""
        return tuple(field.name for field in dataclasses.fields(cls))

    @property
    def angular_joints(self):
        """Which actuated joints are angles [rad], one per joint (a
        mechanism with revolute actuators marks them; none by default)."""
        return (False,) * self.n_joints

    @property
    def n_joints(self):
        """Number of actuated joints."""
        return len(self.joint_names)

    @property
    def pose_size(self):
        """Number of pose coordinates."""
        return len(self.pose_names)

    @property
    @abc.abstractmethod
    def scale(self):
        """Characteristic length [length unit]."""

    @abc.abstractmethod
    def solve(self, joints):
        """All real direct-kinematic solutions of many joint vectors.

        Parameters
        ----------
        joints : ndarray, shape (n, n_joints)

        Returns
        -------
        count : ndarray of uint8, shape (n,)
        poses : ndarray, shape (n, max_solutions, pose_size)
            Sorted in a fixed order per joint vector, NaN beyond ``count``.
        """

    def leg_joints(self, poses):
        """Each leg's actuated joint at poses, on each of its branches (the
        closed-form inverse kinematics, leg by leg).

        Parameters
        ----------
        poses : ndarray, shape (..., pose_size)
            Finite.

        Returns
        -------
        ndarray, shape (..., n_joints, leg_branches)
            [joint unit], angles in (-pi, pi]; branch 0 is sign +1 of
            :attr:`working_modes`, branch 1 sign -1; NaN where the leg
            cannot reach the pose.

        Raises
        ------
        NotImplementedError
            For mechanisms without a closed-form inverse kinematics.
        """
        raise NotImplementedError(f"{self.kind} has no inverse kinematics")

    @property
    def working_modes(self):
        """The working modes, one branch sign (+1 or -1) per leg, in the
        order of :meth:`inverse_kinematics`: every combination, +1 before
        -1 and the first leg's sign varying slowest.

        Returns
        -------
        ndarray of int8, shape (leg_branches ** n_joints, n_joints)
        """
        signs = (1, -1)[:self.leg_branches]
        return np.array(list(itertools.product(signs, repeat=self.n_joints)), dtype=np.int8)

    def inverse_kinematics(self, poses):
        """The joints of every working mode of platform poses.

        Parameters
        ----------
        poses : array_like, shape (..., pose_size)
            Finite (:attr:`pose_names`, angles [rad]).

        Returns
        -------
        ndarray, shape (..., n_modes, n_joints)
            The joints [joint unit] of each working mode of
            :attr:`working_modes`, angles in (-pi, pi]; a row of NaN where a
            leg of that mode cannot reach the pose.  Whether they lie in a
            joint box is the caller's to check.

        Raises
        ------
        InvalidInputError
            If the poses are not finite numbers of shape (..., pose_size).
        """
        poses = finite_vectors(poses, "poses", self.pose_size)
        legs = self.leg_joints(poses)
        branch = (1 - self.working_modes.astype(np.intp)) // 2
        joints = legs[..., np.arange(self.n_joints), branch]
        return np.where(np.isnan(joints).any(axis=-1, keepdims=True), np.nan, joints)

    @abc.abstractmethod
    def margin(self, poses, joints):
        """Signed, normalised distance from a parallel singularity, shape (...):
        0 on one, in [-1, 1], its sign the aspect.

        ``joints`` (shape (..., n_joints), broadcast against ``poses``) are
        those the poses solve: a mechanism whose pose alone does not fix its
        passive joints (a five-bar's elbows) needs them.
        """

    @abc.abstractmethod
    def predict(self, poses, joints_from, joints_to):
        """Euler predictor: poses moved for a change of joints, shape of ``poses``."""

    @property
    @abc.abstractmethod
    def predict_kernel(self):
        """:meth:`predict` compiled by numba, for the solutions of one joint
        vector at a time: what continuity's screen calls millions of times.

        Returns
        -------
        (first-class function, ndarray)
            A function compiled for :data:`PREDICT_KERNEL_SIGNATURE`
            (:func:`first_class`) and the ``parameters`` array it takes.
        """

    @abc.abstractmethod
    def correct(self, poses, joints, iterations):
        """Newton corrector on the constraint equations at fixed joints."""

    @abc.abstractmethod
    def residual(self, poses, joints):
        """Constraint residuals ``F(q, x)``, shape (..., n_joints)."""

    @abc.abstractmethod
    def step(self, pose, joints_from, joints_to):
        """One predictor-corrector step of one pose (sequences of floats).

        Returns
        -------
        (tuple of float, float) or None
            The pose at ``joints_to`` and its margin, or None when the
            corrector does not converge.
        """

    @property
    def step_kernel(self):
        """:meth:`step` compiled by numba, if the mechanism has it.

        Returns
        -------
        (first-class function, ndarray) or None
            A function compiled for :data:`STEP_KERNEL_SIGNATURE` (a numba
            dispatcher, or better :func:`first_class` of it) and the
            ``parameters`` array it takes; None (the default) makes the
            validator call :meth:`step` from the interpreter.
        """
        return None

    @abc.abstractmethod
    def to_dict(self):
        """Plain data with a ``"kind"`` key, for JSON, messages and cache keys."""

    def refine_cusp(self, pose, fixed):
        """Newton from a pose to a cusp point of a 2-D slice: a point where
        three direct-kinematic solutions merge.

        Parameters
        ----------
        pose : array_like, shape (pose_size,)
            A pose near the cusp.
        fixed : mapping of int to float
            The joints the slice fixes and their values.

        Returns
        -------
        (ndarray, ndarray) or None
            The cusp's pose and joints, or None when Newton does not converge.

        Raises
        ------
        NotImplementedError
            For mechanisms (or slices) without cusp equations.
        """
        raise NotImplementedError(f"{self.kind} has no cusp equations")

    def body_outline(self, poses, joints):
        """The moving bodies of configurations as segments and polygons
        between named joint points, and the passive joint angles.

        Parameters
        ----------
        poses : ndarray, shape (..., pose_size)
        joints : ndarray, shape (..., n_joints)
            The joints the poses solve.

        Returns
        -------
        links : list of (str, int, (str, str), ndarray, ndarray, bool)
            Per link: its name, its leg (from 0), the names of its end
            points, the end points (shape (..., 2) each) [length unit] and
            whether it is a prismatic leg (a housing and a rod).
        plates : list of (str, tuple of str, ndarray)
            Per plate (the platform): its name, the names of its vertices and
            the vertices, convex, shape (..., k, 2) [length unit].
        passive : list of (str, ndarray)
            Per passive joint: its name and its angle, shape (...) [rad].

        Raises
        ------
        NotImplementedError
            For mechanisms that do not describe their bodies.
        """
        raise NotImplementedError(f"{self.kind} does not describe its bodies")

    def check_joints(self, joints):
        """Raise ``InvalidInputError`` for joint values the mechanism cannot take.

        The default accepts any finite values.
        """
        if not np.all(np.isfinite(joints)):
            raise InvalidInputError(f"joints must be finite, got {np.asarray(joints).tolist()}")

    def aspect(self, poses, joints=None):
        """``sign(margin)``: +1 or -1, 0 exactly on a singularity, int8, shape
        (...); ``joints`` as :meth:`margin`'s, which says when they are needed."""
        return np.sign(self.margin(poses, joints)).astype(np.int8)

    def pose_difference(self, a, b):
        """``a - b`` with angles wrapped and measured as arc length at ``scale``."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if a.ndim == 1 and a.shape == b.shape:
            # Two poses, as the validator compares at every path's end:
            # broadcasting them would cost more than the difference.
            return _pose_differences(a[None], b[None], np.array(self.angular, dtype=bool),
                                     float(self.scale))[0]
        shape, a, b = _pose_rows(a, b)
        return _pose_differences(a, b, np.array(self.angular, dtype=bool),
                                 float(self.scale)).reshape(shape)

    def pose_distance(self, a, b):
        """Euclidean norm of :meth:`pose_difference` [length unit], shape (...)."""
        shape, a, b = _pose_rows(a, b)
        distance = _pose_distances(a, b, np.array(self.angular, dtype=bool), float(self.scale))
        return distance.reshape(shape[:-1])[()]

    def separation(self, poses, count):
        """Distance (:meth:`pose_distance`) from each solution of a cell to the
        nearest other solution of that cell.

        Parameters
        ----------
        poses : ndarray, shape (n, max_solutions, pose_size)
            Solutions of n cells, as :meth:`solve` gives them.
        count : ndarray of int, shape (n,)
            Number of solutions of each cell.

        Returns
        -------
        ndarray, shape (n, max_solutions)
            inf for a cell's only solution, NaN beyond ``count``.
        """
        return _separation(np.asarray(poses, dtype=float), np.asarray(count),
                           np.array(self.angular, dtype=bool), float(self.scale))

    def wrap_scalar(self, pose):
        """One pose (sequence of floats) with its angles wrapped, as a tuple."""
        return tuple(math.atan2(math.sin(v), math.cos(v)) if angle else float(v)
                     for v, angle in zip(pose, self.angular))


def _pose_rows(a, b):
    """Poses ``a`` and ``b`` broadcast together: their shape, and each as
    rows (n, pose size)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    shape = np.broadcast_shapes(a.shape, b.shape)
    size = shape[-1]
    return (shape, np.broadcast_to(a, shape).reshape(-1, size),
            np.broadcast_to(b, shape).reshape(-1, size))


@numba.njit(cache=True, nogil=True, inline="always")
def _coordinate_difference(a, b, angular, scale):
    """``a - b`` of one coordinate; an angle's wrapped into [-pi, pi) as
    ``pi - remainder(pi - d, 2 pi)`` (numpy's remainder, to the bit) and
    measured as arc length at ``scale``."""
    difference = a - b
    if angular:
        turned = np.pi - difference
        # The remainder of a value within a turn is exact: the value, or
        # the value plus a turn; fmod, slow, only for the others.
        if not abs(turned) < 2 * np.pi:
            turned = np.remainder(turned, 2 * np.pi)
        elif turned < 0:
            turned += 2 * np.pi
        difference = (np.pi - turned) * scale
    return difference


@numba.njit(cache=True, nogil=True)
def compiled_pose_distance(a, b, angular, scale):
    """:meth:`Mechanism.pose_distance` of two poses, compiled, for kernels.

    The squares are summed from the first coordinate on, as numpy's norm
    sums them, so that it agrees with the method to the bit.

    Parameters
    ----------
    a, b : ndarray, shape (pose_size,)
        The poses [pose units].
    angular : ndarray of bool, shape (pose_size,)
        Which coordinates are angles [rad], compared the short way round.
    scale : float
        The length [length unit] that makes an angle a length.

    Returns
    -------
    float
        [length unit].
    """
    total = 0.0
    for k in range(a.size):
        difference = _coordinate_difference(a[k], b[k], angular[k], scale)
        total += difference * difference
    return math.sqrt(total)


@numba.njit(cache=True, nogil=True)
def _pose_differences(a, b, angular, scale):
    """:meth:`Mechanism.pose_difference` of the rows of ``a`` and ``b``,
    shape (n, pose_size)."""
    out = np.empty(a.shape)
    for r in range(a.shape[0]):
        for k in range(a.shape[1]):
            out[r, k] = _coordinate_difference(a[r, k], b[r, k], angular[k], scale)
    return out


@numba.njit(cache=True, nogil=True)
def _pose_distances(a, b, angular, scale):
    """:func:`compiled_pose_distance` of the rows of ``a`` and ``b``, shape
    (n, pose_size): continuity and the field ask for millions, and numpy's temporaries cost
    more than the arithmetic."""
    out = np.empty(a.shape[0])
    for r in range(a.shape[0]):
        out[r] = compiled_pose_distance(a[r], b[r], angular, scale)
    return out


@numba.njit(cache=True, nogil=True)
def _separation(poses, count, angular, scale):
    """:meth:`Mechanism.separation` of checked arrays."""
    out = np.full(poses.shape[:2], np.nan)
    for cell in range(poses.shape[0]):
        for slot in range(count[cell]):
            nearest = np.inf
            for other in range(count[cell]):
                if other != slot:
                    distance = compiled_pose_distance(poses[cell, other], poses[cell, slot],
                                                      angular, scale)
                    # np.minimum's: a NaN, once met, stays.
                    if nearest == nearest and not nearest <= distance:
                        nearest = distance
            out[cell, slot] = nearest
    return out
