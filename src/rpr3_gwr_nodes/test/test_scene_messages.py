"""Scenes as rpr3_gwr_msgs/Scene messages, in process: what the planner and
the driver read from their ``scene`` topic, without a ROS graph."""

import math

import pytest
from geometry_msgs.msg import Point
from rclpy.serialization import serialize_message
from rpr3_gwr_core.exceptions import InvalidInputError
from rpr3_gwr_core.world import scene_from_dict
from rpr3_gwr_msgs.msg import JointRange, Obstacle, Scene
from std_msgs.msg import Header

from rpr3_gwr_nodes.conversions import (MAX_SCENE_MESSAGE_BYTES, is_empty_scene, scene_from_msg,
                                        scene_msg_from_bytes, scene_to_msg)

DOCUMENT = {
    "obstacles": [{"id": "post", "disc": {"center": [5.0, 12.0], "radius": 1.5}},
                  {"id": "plate", "polygon": [[-10.0, 30.0], [-6.0, 30.0], [-6.0, 34.0]]}],
    "limits": {"strokes": {"rho2": [3.0, 40.0]}, "passive": {"base1": [0.0, 2.0]},
               "obstacle_clearance": 0.25}}


def _disc(oid="disc", radius=1.0):
    return Obstacle(id=oid, type=Obstacle.DISC, center=Point(x=40.0, y=40.0), radius=radius)


@pytest.mark.parametrize("frame", ["base", ""])
def test_a_scene_crosses_as_a_message_and_back(frame):
    scene = scene_from_dict(DOCUMENT)
    msg = scene_to_msg(scene, Header(frame_id=frame))
    assert [o.type for o in msg.obstacles] == [Obstacle.POLYGON, Obstacle.DISC]
    assert scene_from_msg(msg).to_dict() == scene.to_dict()


@pytest.mark.parametrize("msg, words", [
    (Scene(header=Header(frame_id="map"), obstacles=[_disc()]), "frame 'map'"),
    (Scene(obstacles=[_disc(oid="")]), "has no id"),
    (Scene(obstacles=[Obstacle(id="box", type=7)]), "has type 7"),
    (Scene(strokes=[JointRange(name="rho2", min=1.0, max=40.0)] * 2), "named twice"),
    (Scene(obstacles=[_disc(radius=-1.0)]), "radius must be positive"),
    (Scene(obstacles=[_disc(radius=math.inf)]), "radius must be a finite number"),
    (Scene(strokes=[JointRange(name="rho2", min=40.0, max=1.0)]), "min 40.0 above max 1.0"),
    (Scene(obstacles=[_disc()], obstacle_clearance=math.nan),
     "obstacle_clearance must be a finite number"),
])
def test_a_malformed_scene_message_is_refused(msg, words):
    with pytest.raises(InvalidInputError, match=words):
        scene_from_msg(msg)


def test_a_scene_without_obstacles_or_ranges_is_no_scene():
    assert is_empty_scene(scene_from_msg(Scene()))
    # Its clearance alone keeps nothing away.
    assert is_empty_scene(scene_from_msg(Scene(obstacle_clearance=1.0)))
    assert not is_empty_scene(scene_from_msg(Scene(obstacles=[_disc()])))
    assert not is_empty_scene(scene_from_msg(Scene(
        strokes=[JointRange(name="rho2", min=1.0, max=40.0)])))


def test_a_serialized_scene_is_read_unless_longer_than_a_scene_may_be():
    msg = scene_to_msg(scene_from_dict(DOCUMENT), Header(frame_id="base"))
    data = serialize_message(msg)
    assert scene_msg_from_bytes(data) == msg
    long = Scene(obstacles=[_disc(oid=f"disc{k}") for k in range(3000)])
    data = serialize_message(long)
    assert len(data) > MAX_SCENE_MESSAGE_BYTES
    with pytest.raises(InvalidInputError, match="refused unread"):
        scene_msg_from_bytes(data)
