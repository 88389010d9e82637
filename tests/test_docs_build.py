"""The documentation builds without a warning, and its ROS interface page
names every parameter, topic, service, action and interface the nodes
declare, so that the reference cannot drift from the code."""

import ast
import pathlib
import subprocess
import sys

import pytest

pytestmark = pytest.mark.ros

ROOT = pathlib.Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
NODES = ROOT / "src" / "rpr3_gwr_nodes" / "rpr3_gwr_nodes"
MSGS = ROOT / "src" / "rpr3_gwr_msgs"
ROS_PAGE = DOCS / "reference" / "ros.rst"
# Where the first positional argument is the name: the parameter of
# declare_parameter, the topic or service of the others (after the type).
_NAME_ARGUMENT = {"declare_parameter": 0, "create_publisher": 1, "create_subscription": 1,
                  "create_service": 1, "ActionServer": 2}


def _callee(call):
    function = call.func
    return function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", None)


def _declared_names(tree):
    """Names given as string constants to the calls of ``_NAME_ARGUMENT``,
    directly or through a local helper that passes its own first argument
    on (the driver's ``positive(name, ...)``)."""
    names = set()
    forwarders = {}
    for function in ast.walk(tree):
        if not isinstance(function, ast.FunctionDef) or not function.args.args:
            continue
        own = {a.arg for a in function.args.args}
        for call in ast.walk(function):
            if (isinstance(call, ast.Call) and _callee(call) == "declare_parameter"
                    and call.args and isinstance(call.args[0], ast.Name)
                    and call.args[0].id in own):
                forwarders[function.name] = [a.arg for a in function.args.args].index(
                    call.args[0].id)
    for call in ast.walk(tree):
        if not isinstance(call, ast.Call):
            continue
        position = _NAME_ARGUMENT.get(_callee(call), forwarders.get(_callee(call)))
        if position is None or len(call.args) <= position:
            continue
        argument = call.args[position]
        if isinstance(argument, ast.Constant) and isinstance(argument.value, str):
            names.add(argument.value)
    return names


def _node_names():
    names = set()
    for source in sorted(NODES.glob("*.py")):
        names |= _declared_names(ast.parse(source.read_text(), str(source)))
    return names


def test_docs_build_without_warnings(tmp_path):
    # -E: read every page again, so a warning is never hidden by a cache.
    result = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
         str(DOCS), str(tmp_path / "html")],
        cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    assert (tmp_path / "html" / "reference" / "ros.html").is_file()


def test_ros_reference_names_every_parameter_and_interface():
    page = ROS_PAGE.read_text()
    declared = _node_names()
    # The nodes declare their parameters, topics and services.
    assert {"clearance", "mechanism_file", "plan_path", "execute_trajectory"} <= declared
    missing = sorted(name for name in declared if f"``{name}``" not in page)
    assert not missing, f"{ROS_PAGE.relative_to(ROOT)} does not document {missing}"
    interfaces = sorted(p.name for kind in ("msg", "srv", "action")
                        for p in (MSGS / kind).glob(f"*.{kind}"))
    assert interfaces
    undocumented = [name for name in interfaces if f"/{name}" not in page]
    assert not undocumented, f"{ROS_PAGE.relative_to(ROOT)} does not include {undocumented}"
