"""The suite's interfaces keep the conventions of common_interfaces, nav2_msgs
and control_msgs: every field documented where it is declared, ``Header``
first in a stamped message, and each result code a typed UPPER_CASE constant
next to an error string."""

import importlib
import pathlib

import pytest

pytestmark = pytest.mark.ros

PACKAGE = pathlib.Path(__file__).resolve().parents[1]
FILES = sorted(p for kind in ("msg", "srv", "action") for p in (PACKAGE / kind).glob(f"*.{kind}"))
CODE_FIELDS = {"error_code": "ERROR_"}


def _parts(path):
    """The generated classes of an interface file: the message, or a
    service's request and response, or an action's goal, result and feedback."""
    module = importlib.import_module(f"rpr3_gwr_msgs.{path.parent.name}")
    interface = getattr(module, path.stem)
    if path.parent.name == "msg":
        return [interface]
    if path.parent.name == "srv":
        return [interface.Request, interface.Response]
    return [interface.Goal, interface.Result, interface.Feedback]


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


def test_the_interface_files_are_the_ones_generated():
    assert len(FILES) == 26
    for path in FILES:
        assert _parts(path)


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_a_header_comes_first(path):
    for part in _parts(path):
        types = list(part.get_fields_and_field_types().values())
        if "std_msgs/Header" in types:
            assert types[0] == "std_msgs/Header", f"{part.__name__}: the header is not first"


@pytest.mark.parametrize("path", FILES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_result_codes_are_typed_constants_beside_an_error_string(path):
    for part in _parts(path):
        fields = part.get_fields_and_field_types()
        for field, prefix in CODE_FIELDS.items():
            if field not in fields:
                continue
            assert fields["error_msg"] == "string", f"{part.__name__} has no error_msg"
            codes = {name: getattr(part, name) for name in dir(part)
                     if name.startswith(prefix) and name.isupper()}
            if not codes:  # an action's result: its constants open the file
                codes = {name: getattr(part, name) for name in dir(part)
                         if name.isupper() and isinstance(getattr(part, name), int)}
            assert codes, f"{part.__name__}.{field} has no constants"
            assert len(set(codes.values())) == len(codes), f"{part.__name__}: codes repeat"
            assert fields[field] == "uint8" and all(0 <= v < 256 for v in codes.values())
            assert 0 in codes.values(), f"{part.__name__}: no code for success"


def test_a_plan_request_left_at_its_defaults_asks_for_the_smoothed_answer():
    from rpr3_gwr_msgs.srv import PlanPath

    request = PlanPath.Request()
    assert not request.skip_smoothing and not request.feasibility_only
    assert request.time_limit == 0.0 and request.max_velocity == 0.0
