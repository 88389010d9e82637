"""The launch file cannot run here (no launch on PyPI), so it is read: it
starts the nodes of the suite launcher's table (rpr3_gwr_nodes.suite_launcher,
which runs here), every executable of that table is a console script of the
package, every parameter it sets is one its node declares, of the type its
launch argument is converted to, every launch argument it uses is declared,
and colcon installs it.  The shipped params file (config/params/suite.yaml)
names only parameters its nodes declare, with the values the suite starts
them with."""

import ast
import importlib
import pathlib

import pytest
import yaml
from rcl_interfaces.msg import ParameterType
from rclpy.node import Node as RclpyNode
from rclpy.parameter import Parameter
from rpr3_gwr_nodes.suite_launcher import ARGUMENTS, NODES, parameter_value

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "rpr3_gwr_nodes"
LAUNCH = PACKAGE / "launch" / "suite.launch.py"
PARAMS = ROOT / "config" / "params" / "suite.yaml"
# The parameter type each kind of launch argument becomes.
TYPES = {str: ParameterType.PARAMETER_STRING, float: ParameterType.PARAMETER_DOUBLE,
         bool: ParameterType.PARAMETER_BOOL, list: ParameterType.PARAMETER_DOUBLE_ARRAY}
# Parameters the params file leaves to the node, its default depending on
# the mechanism file, the machine or the time; the file says so in comments.
LEFT_TO_THE_NODE = {"roadmap_builder": {"fixed_value", "ranges"},
                    "planner": {"plan_workers"},
                    "rpr3_driver": {"initial_configuration"},
                    "trajectory_recorder": {"bag_path"},
                    "scene_publisher": set()}
# Declared by every rclpy node, not by the suite's.
ROS_OWN = {"use_sim_time", "start_type_description_service"}


def _keyword(call, name):
    return next((k.value for k in call.keywords if k.arg == name), None)


def _console_scripts():
    """Entry points of setup.py: executable -> module."""
    setup = ast.parse((PACKAGE / "setup.py").read_text())
    scripts = next(ast.literal_eval(k.value)["console_scripts"] for node in ast.walk(setup)
                   if isinstance(node, ast.Call) for k in node.keywords
                   if k.arg == "entry_points")
    return {name.strip(): target.split(":")[0].strip()
            for name, target in (line.split("=") for line in scripts)}


def _node(executable, context, tmp_path, overrides=()):
    """The real node class of a console script, created on ``context``."""
    scripts = _console_scripts()
    assert executable in scripts, f"{executable} is no console script of rpr3_gwr_nodes"
    module = importlib.import_module(scripts[executable])
    node_types = [v for v in vars(module).values() if isinstance(v, type)
                  and issubclass(v, RclpyNode) and v.__module__ == module.__name__]
    assert len(node_types) == 1
    # A recorder opens its bag when created: keep it in the test's directory.
    bag = [Parameter("bag_path", value=str(tmp_path / "bag"))]
    return node_types[0](context=context, parameter_overrides=[
        *overrides, *(bag if executable == "trajectory_recorder" else [])])


def test_the_launch_file_starts_the_five_nodes_of_the_launchers_table():
    tree = ast.parse(LAUNCH.read_text())
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)
                and node.module == "rpr3_gwr_nodes.suite_launcher" for alias in node.names}
    assert "NODES" in imported
    started = [node for node in ast.walk(tree) if isinstance(node, ast.Call)
               and getattr(node.func, "id", None) == "Node"]
    assert len(started) == 1 and ast.unparse(_keyword(started[0], "executable")) == "executable"
    assert sorted(e for e, *_ in NODES) == [
        "planner", "roadmap_builder", "rpr3_driver", "scene_publisher", "trajectory_recorder"]


@pytest.mark.parametrize("executable, arguments, fixed",
                         [(e, a, f) for e, _, a, f in NODES])
def test_every_node_and_parameter_of_the_launch_file_exists(ros_context, tmp_path, executable,
                                                            arguments, fixed):
    node = _node(executable, ros_context, tmp_path)
    try:
        missing = [name for name in (*arguments, *fixed) if not node.has_parameter(name)]
        assert not missing, f"{executable} declares no {missing}"
        # A launch argument converted by parameter_value has the declared type.
        for name in arguments:
            assert node.describe_parameter(name).type == TYPES[ARGUMENTS[name][0]], name
    finally:
        node.destroy_node()


def test_launch_argument_texts_become_the_declared_types():
    assert parameter_value("fixed_value", "13") == 13.0
    assert isinstance(parameter_value("fixed_value", "13"), float)
    assert parameter_value("initial_configuration", "[0, 1.2, 2.25, 0.65]") == [
        0.0, 1.2, 2.25, 0.65]
    assert parameter_value("full", "True") is True
    assert parameter_value("mechanism_file", "config/three_rrr.yaml") == "config/three_rrr.yaml"


@pytest.mark.parametrize("executable", [e for e, *_ in NODES])
def test_the_params_file_holds_declared_parameters_at_the_suites_defaults(
        ros_context, tmp_path, executable):
    sections = yaml.safe_load(PARAMS.read_text())
    assert set(sections) == {e for e, *_ in NODES}
    values = sections[executable]["ros__parameters"]
    fixed = next(f for e, _, _, f in NODES if e == executable)
    node = _node(executable, ros_context, tmp_path)
    try:
        declared = {name for name in node._parameters} - ROS_OWN
        assert set(values) <= declared, f"{executable} declares no {set(values) - declared}"
        assert set(values) | LEFT_TO_THE_NODE[executable] == declared
        for name, value in values.items():
            default = fixed.get(name, node.get_parameter(name).value)
            assert value == default and type(value) is type(default), name
    finally:
        node.destroy_node()
    # The file's values are accepted as the node's parameters (a recorder's
    # bag in a directory of its own: a bag's must not exist).
    (tmp_path / "from_file").mkdir()
    node = _node(executable, ros_context, tmp_path / "from_file",
                 [Parameter(name, value=value) for name, value in values.items()])
    node.destroy_node()


def test_every_launch_argument_used_is_declared():
    tree = ast.parse(LAUNCH.read_text())
    switches = next(node.value for node in ast.walk(tree) if isinstance(node, ast.Assign)
                    and node.targets[0].id == "SWITCHES")
    declared = set(ARGUMENTS) | {entry[0] for entry in ast.literal_eval(switches)}
    # Named in the file: LaunchConfiguration("...") or its helper given("...").
    used = {node.args[0].value for node in ast.walk(tree) if isinstance(node, ast.Call)
            and getattr(node.func, "id", None) in ("LaunchConfiguration", "given")
            and isinstance(node.args[0], ast.Constant)}
    used |= {switch for _, switch, _, _ in NODES if switch}
    used |= {name for _, _, arguments, _ in NODES for name in arguments}
    assert "params_file" in used and used <= declared


def test_colcon_installs_the_launch_file_and_the_launcher():
    install = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes"
    assert (install / "share" / "rpr3_gwr_nodes" / "launch" / "suite.launch.py").exists()
    assert (install / "lib" / "rpr3_gwr_nodes" / "suite").exists()
