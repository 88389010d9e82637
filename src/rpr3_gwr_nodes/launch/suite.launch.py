"""The rpr3-gwr suite on a full ROS 2 Jazzy install:

    ros2 launch rpr3_gwr_nodes suite.launch.py rho1:=17.0 record:=true
    ros2 launch rpr3_gwr_nodes suite.launch.py full:=true

Starts the roadmap builder, the planner and the simulated driver, and with
``record:=true`` a recorder that writes plans, joint states and every marker
to one MCAP bag (open it in Foxglove or Lichtblick).  Keep DDS on this
machine as the README says (the project's Fast DDS profile).
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

ARGUMENTS = [
    ("rho1", "17.0", "Fixed first leg of the roadmap [length unit]"),
    ("step", "0.125", "Grid step of the roadmap [length unit]"),
    ("full", "false", "Build the full 3-DOF roadmap (all legs free) instead of the slice"),
    ("time_scale", "1.0", "Playback speed factor of the simulated driver"),
    ("record", "false", "Also start the bag recorder"),
    ("bag_path", "rpr3_gwr_bags/suite", "Directory of the bag to write (must not exist)"),
]


def generate_launch_description():
    config = {name: LaunchConfiguration(name) for name, _, _ in ARGUMENTS}
    return LaunchDescription([
        *[DeclareLaunchArgument(name, default_value=default, description=description)
          for name, default, description in ARGUMENTS],
        Node(package="rpr3_gwr_nodes", executable="roadmap_builder", name="roadmap_builder",
             output="screen", parameters=[{
                 "rho1": config["rho1"], "step": config["step"],
                 "full": ParameterValue(config["full"], value_type=bool)}]),
        Node(package="rpr3_gwr_nodes", executable="planner", name="planner", output="screen"),
        Node(package="rpr3_gwr_nodes", executable="rpr3_driver", name="rpr3_driver",
             output="screen", parameters=[{"time_scale": config["time_scale"]}]),
        Node(package="rpr3_gwr_nodes", executable="trajectory_recorder",
             name="trajectory_recorder", output="screen",
             condition=IfCondition(config["record"]),
             parameters=[{"bag_path": config["bag_path"], "storage": "mcap",
                          "record_joint_states": True, "record_visualization": True}]),
    ])
