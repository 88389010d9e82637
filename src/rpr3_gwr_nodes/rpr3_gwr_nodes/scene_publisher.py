"""scene_publisher: publishes a scene file for the planner and the driver.

Reads ``scene_file`` (a scene document, YAML as ``config/scenes/*.yaml``,
read by the core's ``load_scene``) and publishes it as rpr3_gwr_msgs/Scene
on ``scene`` (reliable, transient local: the planner and the driver get the
latest one whenever they start), frame ``base``.  Setting ``scene_file`` at
run time publishes the new file; a file that cannot be read or is not a
valid scene is refused with the reason, and the parameter and the published
scene stay; empty publishes no scene (a scene message without obstacles and
limits).  Names of joints are checked where the scene is applied: the
planner and the driver refuse a scene for another mechanism.
"""

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rpr3_gwr_core.io.scene_file import load_scene
from rpr3_gwr_core.world import EMPTY_SCENE
from rpr3_gwr_msgs.msg import Scene
from std_msgs.msg import Header

from .conversions import scene_to_msg
from .profiles import BASE_FRAME, LATCHED_QOS
from .spin import run

__all__ = ["ScenePublisher", "main", "USAGE"]

USAGE = """\
usage: ros2 run rpr3_gwr_nodes scene_publisher [-h] [--ros-args ...]

Publishes the scene (obstacles, strokes, passive ranges) of a scene file for
the planner and the driver, latched; setting scene_file at run time
publishes another, a bad file is refused with its reason.

Publishes   scene (rpr3_gwr_msgs/msg/Scene, latched, frame base)
Parameters  scene_file (YAML as config/scenes/*.yaml; '' publishes no scene)
Example     ros2 run rpr3_gwr_nodes scene_publisher --ros-args \\
                -p scene_file:=config/scenes/paper_narrowed.yaml
"""


class ScenePublisher(Node):
    """Publishes the scene of ``scene_file``."""

    def __init__(self, **kwargs):
        super().__init__("scene_publisher", **kwargs)
        self.declare_parameter("scene_file", "", ParameterDescriptor(
            description="Scene document to publish (YAML, as config/scenes/*.yaml); empty "
                        "publishes no scene; set at run time to publish another"))
        self.publisher = self.create_publisher(Scene, "scene", LATCHED_QOS)
        # The scene of a new file, read when it is checked, published once set.
        self._checked = None
        self.add_on_set_parameters_callback(self._check)
        self.add_post_set_parameters_callback(self._set)
        path = self.get_parameter("scene_file").value
        # A bad file at start publishes nothing: the nodes keep what they have.
        try:
            self._publish(self._read(path), path)
        except Exception as exc:  # GWRError: a bad file; anything else a bug
            self.get_logger().error(f"not publishing a scene: {exc}")

    @staticmethod
    def _read(path):
        return load_scene(path) if path else EMPTY_SCENE

    def _check(self, parameters):
        """Accept a ``scene_file`` that reads as a scene, refuse any other."""
        for parameter in parameters:
            if parameter.name == "scene_file":
                try:
                    self._checked = self._read(parameter.value)
                except Exception as exc:  # GWRError: a bad file; anything else a bug
                    return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _set(self, parameters):
        for parameter in parameters:
            if parameter.name == "scene_file":
                self._publish(self._checked, parameter.value)

    def _publish(self, scene, path):
        header = Header(stamp=self.get_clock().now().to_msg(), frame_id=BASE_FRAME)
        self.publisher.publish(scene_to_msg(scene, header))
        self.get_logger().info(f"published the scene of {path} on {self.publisher.topic_name}: "
                               f"{len(scene.polygons) + len(scene.discs)} obstacle(s)"
                               if path else f"published no scene on {self.publisher.topic_name}")


def main(args=None):
    return run(ScenePublisher, SingleThreadedExecutor, args, usage=USAGE)
