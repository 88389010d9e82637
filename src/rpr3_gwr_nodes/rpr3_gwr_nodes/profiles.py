"""What the suite's nodes share, as nav2's ``qos_profiles``: the QoS of each
kind of topic and the frame of the mechanism's base."""

from rclpy.qos import (DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy,
                       qos_profile_sensor_data)

__all__ = ["LATCHED_QOS", "STATE_QOS", "SENSOR_QOS", "SERVICE_QOS", "TF_QOS", "BASE_FRAME"]

# Maps, roadmaps and scenes (and the scene each node applies), as nav2's map
# server: the latest one, to late joiners too (subscribers use the same
# profile).
LATCHED_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Services many clients call at once.  One writer sends every client's
# response and, reliable but keeping the last 10 only (the services' default),
# it overwrote responses not yet acknowledged when more than 10 were in flight
# on a loaded machine: a request was then lost for good (about one in 2,000
# with 8 clients on 2 cores).  Clients calling at a high rate use it too:
# with their default history, 8 clients in the planner's process had one
# request in a few thousand never reach it at 200 requests/s.
SERVICE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                         reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.VOLATILE)
# What the driver publishes (joint states, platform pose and markers at the
# control rate, diagnostics): reliable, as ros2_control's
# joint_state_broadcaster publishes joint states.  A best-effort writer
# serves no reader that asks for reliable, as create_subscription(..., 10)
# does by default (robot_state_publisher, RViz's displays); a reliable one
# serves both kinds.  Keeping the last 10, a slow reader costs the writer no
# more than their resends.
STATE_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10,
                       reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE)
# Readers of those streams that would rather skip a sample than wait for its
# resend (the recorder): best effort matches a reliable writer too.
SENSOR_QOS = qos_profile_sensor_data
# /tf, as tf2_ros's TransformBroadcaster (DynamicBroadcasterQoS): reliable,
# volatile, the last 100, so that RViz and every TransformListener take it.
TF_QOS = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                    reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.VOLATILE)
# The frame of the base points A1..A3 and of every pose.
BASE_FRAME = "base"
