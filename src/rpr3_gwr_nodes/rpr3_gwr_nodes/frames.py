"""The mechanism's frames, as TF transforms from the fixed frame ``base``.

Each link of the mechanism's body outline (:meth:`Mechanism.body_outline`:
the 3-RPR's ``leg1..3``, the 3-RRR's and 3-PRR's ``proximal1..3`` and
``distal1..3``, the five-bar's ``proximal1..2`` and ``distal1..2``) has a
frame at its first point (the 3-RPR's ``A_i``, a proximal link's base
joint, a distal link's elbow) whose x axis runs along the link to its
second point; the ``platform`` frame is at the pose's point (``B1`` of the
three-leg mechanisms, the five-bar's end point ``P``) and turned by the
pose's angle (``alpha``; the five-bar's has none).  Frames lie in the base
plane: z is 0 and they turn about z only.  Names are lower case with
underscores, as REP 105's; ``frame_prefix`` goes before each child frame's
name, as robot_state_publisher's.
"""

import math

from geometry_msgs.msg import Quaternion, Transform, TransformStamped, Vector3
from std_msgs.msg import Header

from .profiles import BASE_FRAME

__all__ = ["PLATFORM_FRAME", "frame_names", "frame_transforms"]

PLATFORM_FRAME = "platform"


def frame_names(mechanism, pose, joints):
    """The child frames :func:`frame_transforms` gives, in its order: the
    links', then the platform's."""
    links, _, _ = mechanism.body_outline(pose, joints)
    return [link[0] for link in links] + [PLATFORM_FRAME]


def frame_transforms(mechanism, pose, joints, stamp, frame_prefix=""):
    """The transforms from ``base`` to each link's frame and the platform's.

    Parameters
    ----------
    mechanism : rpr3_gwr_core.mechanisms.Mechanism
    pose : sequence of float, shape (pose_size,)
        The platform's pose [length unit, rad].
    joints : sequence of float, shape (n_joints,)
        The joints it solves [joint unit].
    stamp : builtin_interfaces.msg.Time
    frame_prefix : str
        Put before each child frame's name.

    Returns
    -------
    list of geometry_msgs.msg.TransformStamped
        In the order of :func:`frame_names`; translations [length unit].
    """
    links, _, _ = mechanism.body_outline(pose, joints)
    header = Header(stamp=stamp, frame_id=BASE_FRAME)
    transforms = [_planar(header, frame_prefix + name, start,
                          math.atan2(end[1] - start[1], end[0] - start[0]))
                  for name, _, _, start, end, _ in links]
    angles = [value for value, angular in zip(pose, mechanism.angular) if angular]
    transforms.append(_planar(header, frame_prefix + PLATFORM_FRAME, pose[:2],
                              angles[0] if angles else 0.0))
    return transforms


def _planar(header, child, origin, yaw):
    """A transform in the base plane: to ``origin``, turned by ``yaw`` about z."""
    return TransformStamped(
        header=header, child_frame_id=child,
        transform=Transform(translation=Vector3(x=float(origin[0]), y=float(origin[1])),
                            rotation=Quaternion(z=math.sin(0.5 * yaw), w=math.cos(0.5 * yaw))))
