"""The rpr3-gwr suite on a full ROS 2 Jazzy install:

    ros2 launch rpr3_gwr_nodes suite.launch.py record:=true
    ros2 launch rpr3_gwr_nodes suite.launch.py full:=true
    ros2 launch rpr3_gwr_nodes suite.launch.py mechanism_file:=config/three_rrr.yaml \
        fixed_value:=0.5 initial_configuration:='[0.5, 1.2, 2.25, 0.65]'
    ros2 launch rpr3_gwr_nodes suite.launch.py params_file:=config/params/suite.yaml
    ros2 launch rpr3_gwr_nodes suite.launch.py scene:=true \
        scene_file:=config/scenes/paper_narrowed.yaml

Starts the roadmap builder, the planner and the simulated driver, all three
on one mechanism (``mechanism_file``, the paper's 3-RPR by default; the
builder's slice fixes its first joint at ``fixed_value`` and the driver
starts at ``initial_configuration``, both the mechanism file's home by
default), and with ``record:=true`` a recorder that writes plans, joint
states and every marker to one MCAP bag (open it in Foxglove or
Lichtblick), and with ``scene:=true`` a scene publisher of ``scene_file``:
the planner plans in it, the driver stops before its obstacles.
``params_file`` (nav2's style, a section per node, as
config/params/suite.yaml) applies to every node.  An argument left empty
leaves its parameter to the params file, else to the node's own default; a
given one wins over the file.  Keep DDS on this machine as the README says
(the project's Fast DDS profile).

Without ros2cli (ROS from PyPI wheels) the ``suite`` executable of this
package starts the same nodes, from the same table
(:mod:`rpr3_gwr_nodes.suite_launcher`), with the same arguments as options.
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from rpr3_gwr_nodes.suite_launcher import ARGUMENTS, NODES, parameter_value

SWITCHES = [
    ("record", "false", "Also start the bag recorder"),
    ("scene", "false", "Also start the scene publisher"),
    ("params_file", "", "ROS parameter file (YAML, a section per node, as "
                        "config/params/suite.yaml) applied to every node; empty for none"),
]


def _nodes(context):
    """The nodes, each given only the arguments that are not empty."""
    def given(name):
        return LaunchConfiguration(name).perform(context)

    params_file = [given("params_file")] if given("params_file") else []
    return [
        Node(package="rpr3_gwr_nodes", executable=executable, name=executable, output="screen",
             condition=IfCondition(LaunchConfiguration(switch)) if switch else None,
             # Later entries win: the table's fixed values, the file, the arguments.
             parameters=[entry for entry in (
                 fixed, *params_file,
                 {name: parameter_value(name, given(name)) for name in arguments if given(name)})
                 if entry])
        for executable, switch, arguments, fixed in NODES]


def generate_launch_description():
    return LaunchDescription([
        *[DeclareLaunchArgument(name, default_value="", description=help_text)
          for name, (_, help_text) in ARGUMENTS.items()],
        *[DeclareLaunchArgument(name, default_value=default, description=description)
          for name, default, description in SWITCHES],
        OpaqueFunction(function=_nodes),
    ])
