"""Every generated interface of rpr3_gwr_msgs imports and instantiates, and
the interfaces keep the conventions of common_interfaces, nav2_msgs and
control_msgs: every field documented where it is declared, ``Header`` first
in a stamped message, and each result code a typed UPPER_CASE constant next
to an error string."""

import importlib
import pathlib

from ament_index_python.packages import get_package_share_directory
import pytest

pytestmark = pytest.mark.ros

PACKAGE = pathlib.Path(__file__).resolve().parents[1]
FILES = sorted(p for kind in ("msg", "srv", "action") for p in (PACKAGE / kind).glob(f"*.{kind}"))


def _interfaces():
    share = pathlib.Path(get_package_share_directory("rpr3_gwr_msgs"))
    return sorted((kind, path.stem) for kind in ("msg", "srv", "action")
                  for path in (share / kind).glob(f"*.{kind}"))


def test_the_package_ships_the_designed_interfaces():
    assert _interfaces() == [
        ("action", "ExecuteTrajectory"),
        ("msg", "AssemblyMode"), ("msg", "AxisLinks"), ("msg", "Configuration"), ("msg", "Cusp"),
        ("msg", "FixedJoint"), ("msg", "Gate"), ("msg", "GlobalPath"), ("msg", "Grid"),
        ("msg", "GridAxis"), ("msg", "JointLimits"), ("msg", "JointRange"), ("msg", "Mechanism"),
        ("msg", "MechanismParameter"), ("msg", "NSolutionField"), ("msg", "Obstacle"),
        ("msg", "PlannedPath"), ("msg", "PlatformPose"), ("msg", "Scene"),
        ("msg", "WorkingMode"), ("msg", "WorkspacePatch"), ("msg", "WorkspaceRoadmap"),
        ("srv", "AssemblyModes"), ("srv", "InverseKinematics"), ("srv", "PlanPath"),
        ("srv", "ResetDriver"),
    ]


def _parts(kind, name):
    """The generated classes of an interface: the message, or a service's
    request and response, or an action's goal, result and feedback."""
    interface = getattr(importlib.import_module(f"rpr3_gwr_msgs.{kind}"), name)
    parts = {"msg": (), "srv": ("Request", "Response"),
             "action": ("Goal", "Result", "Feedback")}[kind]
    return [getattr(interface, p) for p in parts] or [interface]


def test_every_interface_imports_and_instantiates():
    for kind, name in _interfaces():
        for part in _parts(kind, name):
            instance = part()
            assert type(instance).__name__ == part.__name__


def test_constants_of_each_group_are_distinct():
    from rpr3_gwr_msgs.action import ExecuteTrajectory
    from rpr3_gwr_msgs.msg import AssemblyMode
    from rpr3_gwr_msgs.srv import AssemblyModes, PlanPath, ResetDriver

    for cls, prefix in ((PlanPath.Response, "ERROR_"), (PlanPath.Response, "FEASIBILITY_"),
                        (ResetDriver.Response, "ERROR_"), (ExecuteTrajectory.Result, ""),
                        (AssemblyModes.Response, "ERROR_"), (AssemblyMode, "FEASIBILITY_")):
        values = [getattr(cls, n) for n in dir(cls) if n.isupper() and n.startswith(prefix)
                  and isinstance(getattr(cls, n), int)]
        assert len(values) == len(set(values)) > 3


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_field_and_constant_is_documented_where_it_is_declared(path):
    """Each run of declarations starts under a comment."""
    lines = path.read_text().splitlines()
    for number, line in enumerate(lines):
        text = line.strip()
        if not text or text.startswith("#") or text == "---":
            continue
        above = lines[number - 1].strip() if number else ""
        assert above and above != "---", \
            f"{path.name}:{number + 1}: {text!r} has no comment above its block"


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_a_header_comes_first(path):
    for part in _parts(path.parent.name, path.stem):
        types = list(part.get_fields_and_field_types().values())
        if "std_msgs/Header" in types:
            assert types[0] == "std_msgs/Header", f"{part.__name__}: the header is not first"


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_result_codes_are_typed_constants_beside_an_error_string(path):
    for part in _parts(path.parent.name, path.stem):
        fields = part.get_fields_and_field_types()
        if "error_code" not in fields:
            continue
        assert fields["error_msg"] == "string", f"{part.__name__} has no error_msg"
        codes = {name: getattr(part, name) for name in dir(part)
                 if name.startswith("ERROR_") and name.isupper()}
        if not codes:  # an action's result: its constants open the file
            codes = {name: getattr(part, name) for name in dir(part)
                     if name.isupper() and isinstance(getattr(part, name), int)}
        assert codes, f"{part.__name__}.error_code has no constants"
        assert fields["error_code"] == "uint8" and all(0 <= v < 256 for v in codes.values())
        assert 0 in codes.values(), f"{part.__name__}: no code for success"


def test_a_plan_request_left_at_its_defaults_asks_for_the_smoothed_answer():
    from rpr3_gwr_msgs.srv import PlanPath

    request = PlanPath.Request()
    assert not request.skip_smoothing and not request.feasibility_only
    assert request.time_limit == 0.0 and request.max_velocity == 0.0
