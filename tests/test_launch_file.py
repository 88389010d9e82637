"""The launch file cannot run here (no launch on PyPI), so it is read: every
executable it starts is a console script of the package, every parameter it
sets is one its node declares, every launch argument it uses is declared,
and colcon installs it."""

import ast
import importlib
import pathlib

import pytest
from rclpy.node import Node as RclpyNode
from rclpy.parameter import Parameter

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "rpr3_gwr_nodes"
LAUNCH = PACKAGE / "launch" / "suite.launch.py"


def _keyword(call, name):
    return next((k.value for k in call.keywords if k.arg == name), None)


def _started_nodes():
    """(executable, parameter names) of each launch_ros Node(...) in the file."""
    found = []
    for call in ast.walk(ast.parse(LAUNCH.read_text())):
        if isinstance(call, ast.Call) and getattr(call.func, "id", None) == "Node":
            executable = ast.literal_eval(_keyword(call, "executable"))
            parameters = _keyword(call, "parameters")
            names = [ast.literal_eval(key) for entry in getattr(parameters, "elts", [])
                     for key in entry.keys]
            found.append((executable, names))
    return found


def _console_scripts():
    """Entry points of setup.py: executable -> module."""
    setup = ast.parse((PACKAGE / "setup.py").read_text())
    scripts = next(ast.literal_eval(k.value)["console_scripts"] for node in ast.walk(setup)
                   if isinstance(node, ast.Call) for k in node.keywords
                   if k.arg == "entry_points")
    return {name.strip(): target.split(":")[0].strip()
            for name, target in (line.split("=") for line in scripts)}


def test_the_launch_file_starts_the_five_nodes():
    assert sorted(e for e, _ in _started_nodes()) == [
        "planner", "roadmap_builder", "rpr3_driver", "scene_publisher", "trajectory_recorder"]


@pytest.mark.parametrize("executable, parameters", _started_nodes())
def test_every_node_and_parameter_of_the_launch_file_exists(ros_context, tmp_path, executable,
                                                            parameters):
    scripts = _console_scripts()
    assert executable in scripts, f"{executable} is no console script of rpr3_gwr_nodes"
    module = importlib.import_module(scripts[executable])
    node_types = [v for v in vars(module).values() if isinstance(v, type)
                  and issubclass(v, RclpyNode) and v.__module__ == module.__name__]
    assert len(node_types) == 1
    # A recorder opens its bag when created: keep it in the test's directory.
    node = node_types[0](context=ros_context, parameter_overrides=[
        Parameter("bag_path", value=str(tmp_path / "bag"))] if "bag_path" in parameters else [])
    try:
        missing = [name for name in parameters if not node.has_parameter(name)]
        assert not missing, f"{executable} declares no {missing}"
    finally:
        node.destroy_node()


def test_every_launch_argument_used_is_declared():
    tree = ast.parse(LAUNCH.read_text())
    declared = {entry.elts[0].value for node in ast.walk(tree)
                if isinstance(node, ast.Assign) and node.targets[0].id == "ARGUMENTS"
                for entry in node.value.elts}
    used = {key.value for node in ast.walk(tree) if isinstance(node, ast.Subscript)
            and getattr(node.value, "id", None) == "config" for key in [node.slice]}
    assert used and used <= declared


def test_colcon_installs_the_launch_file():
    installed = (ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "share" / "rpr3_gwr_nodes"
                 / "launch" / "suite.launch.py")
    assert installed.exists()
