"""trajectory_recorder: records planned paths (and, on request, the driver's
joint states) to a rosbag2 bag.

Each plan is recorded twice: its trajectory (``planned_trajectory``, a
standard type any tool reads) and the whole plan with its start and goal
configurations, mode coordinate included (``planned_path``,
rpr3_gwr_msgs/PlannedPath), so that a bag alone says where the driver must
stand to replay it.  The bag describes the suite's types with the
definitions of the installed rpr3_gwr_msgs.

Messages are taken serialized from DDS (``raw=True``) and written unchanged,
by a thread of its own (the storage may only be used by the thread that
opened it, whatever executor spins the node), with the ``rosbags`` library,
so ``ros2 bag info`` and ``ros2 bag play`` of a full Jazzy install read the
bag (format version 9, sqlite3 or MCAP storage, with metadata.yaml).  The bag
is closed, and its metadata written, when the node is destroyed: on SIGINT
too, since ``main`` destroys the node in ``finally``.

Every ``flush_period`` seconds what was written reaches the file (sqlite3:
the transaction is committed; MCAP: the chunk is closed and the file
flushed), so a recorder killed outright (SIGKILL, power loss) loses at most
the last period.  Such a bag has no metadata.yaml: ``rpr3_gwr_recover_bag``
(:mod:`~rpr3_gwr_nodes.bag_recovery`) makes it whole again.

Parameters: ``bag_path`` (default ``rpr3_gwr_bags/<date>_<time>``),
``storage`` (``sqlite3`` or ``mcap``), ``record_joint_states`` (bool),
``record_visualization`` (bool: also the suite's markers and field maps, so
one MCAP file opened in Foxglove shows the plan and its execution),
``flush_period`` [s].
"""

import datetime
import pathlib
import queue
import threading
import time

from nav_msgs.msg import OccupancyGrid
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.storage_sqlite3 import Sqlite3Writer
from rpr3_gwr_msgs.msg import PlannedPath
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from .bag_types import suite_typestore
from .profiles import LATCHED_QOS, SENSOR_QOS
from .spin import run

__all__ = ["TrajectoryRecorder", "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes trajectory_recorder [-h] [--ros-args ...]

Records the planner's trajectories (and, on request, the driver's joint
states and the suite's markers) to a rosbag2 bag, flushed every
flush_period and closed cleanly on SIGINT.

Subscribes  planned_trajectory, planned_path; joint_states with
            record_joint_states; markers and field maps with
            record_visualization
Parameters  bag_path (rpr3_gwr_bags/<date>_<time>, must not exist), storage
            (sqlite3 or mcap), record_joint_states (false),
            record_visualization (false), flush_period (0.5 s); all
            read-only
Example     ros2 run rpr3_gwr_nodes trajectory_recorder --ros-args \\
                -p bag_path:=out/my_bag -p storage:=mcap
"""

_STORAGE = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}
# Topic: (type, type name, QoS) of what record_visualization adds; latched
# topics are taken with the publisher's durability so a late recorder gets them.
_VISUALIZATION = {
    "mechanism_markers": (MarkerArray, "visualization_msgs/msg/MarkerArray", SENSOR_QOS),
    "planned_path_markers": (MarkerArray, "visualization_msgs/msg/MarkerArray", 10),
    "roadmap_markers": (MarkerArray, "visualization_msgs/msg/MarkerArray", LATCHED_QOS),
    "field_count_map": (OccupancyGrid, "nav_msgs/msg/OccupancyGrid", LATCHED_QOS),
    "field_region_map": (OccupancyGrid, "nav_msgs/msg/OccupancyGrid", LATCHED_QOS),
}


class TrajectoryRecorder(Node):
    """Writes planned trajectories (and joint states) to a bag."""

    def __init__(self, **kwargs):
        super().__init__("trajectory_recorder", **kwargs)
        stamp = datetime.datetime.now().strftime("%Y%m%d_%H%M%S")
        self.declare_parameter("bag_path", f"rpr3_gwr_bags/{stamp}", ParameterDescriptor(
            description="Directory of the bag to create (must not exist)", read_only=True))
        self.declare_parameter("storage", "sqlite3", ParameterDescriptor(
            description="rosbag2 storage: sqlite3 or mcap", read_only=True))
        self.declare_parameter("record_joint_states", False, ParameterDescriptor(
            description="Also record the driver's joint_states", read_only=True))
        self.declare_parameter("record_visualization", False, ParameterDescriptor(
            description="Also record the markers and field maps of the builder, the planner "
                        "and the driver", read_only=True))
        self.declare_parameter("flush_period", 0.5, ParameterDescriptor(
            description="Most time between a message's arrival and its reaching the bag's "
                        "file; a killed recorder loses at most this much [s]",
            read_only=True,
            floating_point_range=[FloatingPointRange(from_value=0.01, to_value=60.0)]))
        storage = self.get_parameter("storage").value
        if storage not in _STORAGE:
            raise ValueError(f"storage must be one of {sorted(_STORAGE)}, got {storage!r}")
        self.bag_path = pathlib.Path(self.get_parameter("bag_path").value).resolve()
        self.bag_path.parent.mkdir(parents=True, exist_ok=True)
        topics = {"planned_trajectory": (JointTrajectory, "trajectory_msgs/msg/JointTrajectory",
                                         10),
                  "planned_path": (PlannedPath, "rpr3_gwr_msgs/msg/PlannedPath", 10)}
        if self.get_parameter("record_joint_states").value:
            topics["joint_states"] = (JointState, "sensor_msgs/msg/JointState", SENSOR_QOS)
        if self.get_parameter("record_visualization").value:
            topics.update(_VISUALIZATION)
        self.counts = {topic: 0 for topic in topics}
        self._queue = queue.Queue()
        opened = threading.Event()
        self._thread = threading.Thread(
            target=self._write_loop, daemon=True,
            args=(_STORAGE[storage],
                  {t: (self.resolve_topic_name(t), v[1]) for t, v in topics.items()},
                  self.get_parameter("flush_period").value, opened))
        self._thread.start()
        opened.wait()
        for topic, (msg_type, _, qos) in topics.items():
            self.create_subscription(msg_type, topic, self._enqueue(topic), qos, raw=True)
        self.get_logger().info(f"ready: recording {sorted(topics)} to {self.bag_path}")

    def _write_loop(self, storage, topics, flush_period, opened):
        writer = Writer(self.bag_path, version=9, storage_plugin=storage)
        writer.open()
        typestore = suite_typestore()
        connections = {topic: writer.add_connection(name, type_name, typestore=typestore)
                       for topic, (name, type_name) in topics.items()}
        _make_durable(writer)
        opened.set()
        due = None  # when what was written since the last flush must be in the file
        try:
            while True:
                try:
                    item = self._queue.get(
                        timeout=None if due is None else max(0.0, due - time.monotonic()))
                except queue.Empty:
                    _make_durable(writer)
                    due = None
                    continue
                if item is None:
                    break
                topic, stamp, raw = item
                writer.write(connections[topic], stamp, raw)
                self.counts[topic] += 1
                if due is None:
                    due = time.monotonic() + flush_period
                elif time.monotonic() >= due:
                    _make_durable(writer)
                    due = None
        finally:
            writer.close()

    def close_bag(self):
        """Write what is queued and close the bag (its metadata included);
        later messages are dropped.  Idempotent; destroy_node calls it."""
        if self._thread.is_alive():
            self._queue.put(None)
            self._thread.join()
            self.get_logger().info(f"closed {self.bag_path}: {self.counts}")

    def _enqueue(self, topic):
        def put(raw):
            if self._thread.is_alive():
                self._queue.put((topic, self.get_clock().now().nanoseconds, raw))
        return put

    def destroy_node(self):
        self.close_bag()
        return super().destroy_node()


def _make_durable(writer):
    """Put what ``writer`` holds in memory into its file.

    rosbags (0.11, pinned) keeps one sqlite3 transaction open until close and
    an MCAP chunk in memory until it reaches 1 MiB; committing, and closing
    the chunk, are what its own close does first.  The recorder's SIGKILL
    test guards this use of its storage objects.
    """
    storage = writer.storage
    if isinstance(storage, Sqlite3Writer):
        storage.conn.commit()
        return
    # A chunk without messages would be indexed with an empty time range.
    if storage.chunk.msgs:
        storage.close_chunk()
    storage.bio.flush()


def main(args=None):
    return run(TrajectoryRecorder, SingleThreadedExecutor, args, usage=USAGE)
