"""The manipulator's geometry as read-only parameters, declared the same way
by every node that needs it (the builder and the driver), so one launch
configuration describes one mechanism."""

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rpr3_gwr_core.mechanisms import PAPER_GEOMETRY, ThreeRPR

__all__ = ["declare_geometry"]


def declare_geometry(node):
    """Declare ``a1``, ``a2``, ``a3``, ``d1``, ``d3`` and ``beta`` on ``node``
    (read-only, the paper's geometry by default) and return their ThreeRPR.

    Raises
    ------
    rpr3_gwr_core.exceptions.InvalidInputError
        If the values given do not make a geometry (a flat platform, say).
    """
    g = PAPER_GEOMETRY
    for name, value in (("a1", g.a1), ("a2", g.a2), ("a3", g.a3)):
        node.declare_parameter(name, list(value), ParameterDescriptor(
            description=f"Base joint {name.upper()} (x, y) [length unit]", read_only=True))
    for name, value, side in (("d1", g.d1, "B1B2"), ("d3", g.d3, "B1B3")):
        node.declare_parameter(name, value, ParameterDescriptor(
            description=f"Platform side {side} [length unit]", read_only=True,
            floating_point_range=[FloatingPointRange(from_value=0.0, to_value=1000.0)]))
    node.declare_parameter("beta", g.beta, ParameterDescriptor(
        description="Platform angle at B1 from B1B2 to B1B3 [rad]", read_only=True,
        floating_point_range=[FloatingPointRange(from_value=-3.1416, to_value=3.1416)]))
    value = {name: node.get_parameter(name).value
             for name in ("a1", "a2", "a3", "d1", "d3", "beta")}
    return ThreeRPR(a1=tuple(value["a1"]), a2=tuple(value["a2"]), a3=tuple(value["a3"]),
                    d1=value["d1"], d3=value["d3"], beta=value["beta"])
