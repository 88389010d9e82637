"""The rpr3-gwr suite on a full ROS 2 Jazzy install:

    ros2 launch rpr3_gwr_nodes suite.launch.py record:=true
    ros2 launch rpr3_gwr_nodes suite.launch.py full:=true
    ros2 launch rpr3_gwr_nodes suite.launch.py mechanism_file:=config/three_rrr.yaml
    ros2 launch rpr3_gwr_nodes suite.launch.py scene:=true \
        scene_file:=config/scenes/paper_narrowed.yaml

Starts the roadmap builder, the planner and the simulated driver, all three
on one mechanism (``mechanism_file``, the paper's 3-RPR by default; the
builder's slice fixes its first joint, at the builder's default value: set
another with ``ros2 param set /roadmap_builder fixed_value ...``), and with
``record:=true`` a recorder that writes plans, joint states and every marker
to one MCAP bag (open it in Foxglove or Lichtblick), and with ``scene:=true``
a scene publisher of ``scene_file``: the planner plans in it, the driver
stops before its obstacles.  Keep DDS on this
machine as the README says (the project's Fast DDS profile).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

ARGUMENTS = [
    ("mechanism_file", "", "Mechanism file of the builder, the planner and the driver (YAML, "
                           "as config/*.yaml); empty for the paper's 3-RPR"),
    ("step", "0.0", "Grid step of the roadmap; 0 for the mechanism file's [joint unit]"),
    ("full", "false", "Build the full roadmap (every joint free) instead of the slice"),
    ("time_scale", "1.0", "Playback speed factor of the simulated driver"),
    ("record", "false", "Also start the bag recorder"),
    ("bag_path", "rpr3_gwr_bags/suite", "Directory of the bag to write (must not exist)"),
    ("scene", "false", "Also start the scene publisher"),
    ("scene_file", "", "Scene the scene publisher publishes (YAML, as config/scenes/*.yaml); "
                       "empty for no scene"),
]


def generate_launch_description():
    config = {name: LaunchConfiguration(name) for name, _, _ in ARGUMENTS}
    # A string even when empty (the paper's 3-RPR), not a parameter of no type.
    mechanism_file = ParameterValue(config["mechanism_file"], value_type=str)
    return LaunchDescription([
        *[DeclareLaunchArgument(name, default_value=default, description=description)
          for name, default, description in ARGUMENTS],
        Node(package="rpr3_gwr_nodes", executable="roadmap_builder", name="roadmap_builder",
             output="screen", parameters=[{
                 "mechanism_file": mechanism_file,
                 "step": ParameterValue(config["step"], value_type=float),
                 "full": ParameterValue(config["full"], value_type=bool)}]),
        Node(package="rpr3_gwr_nodes", executable="planner", name="planner", output="screen",
             parameters=[{"mechanism_file": mechanism_file}]),
        Node(package="rpr3_gwr_nodes", executable="rpr3_driver", name="rpr3_driver",
             output="screen", parameters=[{"mechanism_file": mechanism_file,
                                           "time_scale": config["time_scale"]}]),
        Node(package="rpr3_gwr_nodes", executable="trajectory_recorder",
             name="trajectory_recorder", output="screen",
             condition=IfCondition(config["record"]),
             parameters=[{"bag_path": config["bag_path"], "storage": "mcap",
                          "record_joint_states": True, "record_visualization": True}]),
        Node(package="rpr3_gwr_nodes", executable="scene_publisher", name="scene_publisher",
             output="screen", condition=IfCondition(config["scene"]),
             parameters=[{"scene_file": ParameterValue(config["scene_file"], value_type=str)}]),
    ])
