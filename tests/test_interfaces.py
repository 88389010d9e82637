"""Every generated interface of rpr3_gwr_msgs imports and instantiates."""

import importlib
import pathlib

from ament_index_python.packages import get_package_share_directory


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


def test_every_interface_imports_and_instantiates():
    for kind, name in _interfaces():
        cls = getattr(importlib.import_module(f"rpr3_gwr_msgs.{kind}"), name)
        parts = {"msg": ("",), "srv": ("Request", "Response"),
                 "action": ("Goal", "Result", "Feedback")}[kind]
        parts = [getattr(cls, p) if p else cls for p in parts]
        for part in parts:
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
