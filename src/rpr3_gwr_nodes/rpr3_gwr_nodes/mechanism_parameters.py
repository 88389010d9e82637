"""The mechanism as a read-only parameter, declared the same way by every
node that needs it (the builder and the driver), so that one launch
configuration describes one mechanism: ``mechanism_file``, a mechanism file
(:mod:`rpr3_gwr_core.io.mechanism_file`: the mechanism and the box of its
joints), empty for the paper's 3-RPR on the box of
``config/paper_3rpr.yaml``."""

import math

from rcl_interfaces.msg import ParameterDescriptor
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file, mechanism_file_from_dict
from rpr3_gwr_core.paper import PAPER_GEOMETRY, PAPER_GRID
from rpr3_gwr_core.world import EMPTY_SCENE

__all__ = ["declare_mechanism", "PAPER_MECHANISM_FILE", "home_source", "kept_scene"]

# The paper's 3-RPR on its legs' box, every leg sampled as the paper's
# slice samples rho2 and rho3, at home in the paper's first example
# (config/paper_3rpr.yaml).
_LEGS = PAPER_GRID.axes[0]
PAPER_MECHANISM_FILE = mechanism_file_from_dict({
    "mechanism": PAPER_GEOMETRY.to_dict(),
    "joints": [{"name": name, "min": _LEGS.low, "max": _LEGS.high, "step": _LEGS.step}
               for name in PAPER_GEOMETRY.joint_names],
    "home": [17.0, 12.0, 18.0, math.radians(122.82)]})


def declare_mechanism(node):
    """Declare ``mechanism_file`` on ``node`` and return its
    :class:`~rpr3_gwr_core.io.mechanism_file.MechanismFile`.

    Raises
    ------
    rpr3_gwr_core.exceptions.InvalidInputError
        If the file does not describe a mechanism and its box.
    OSError
        If it cannot be read.
    """
    node.declare_parameter("mechanism_file", "", ParameterDescriptor(
        description="Mechanism file (YAML: the mechanism's kind and parameters and the box "
                    "of its joints, as config/*.yaml); empty for the paper's 3-RPR on the "
                    "box of config/paper_3rpr.yaml", read_only=True))
    path = node.get_parameter("mechanism_file").value
    return load_mechanism_file(path) if path else PAPER_MECHANISM_FILE


def home_source(described):
    """Where a mechanism file's default home comes from, for the log."""
    if described.home is not None:
        return "the mechanism file's home"
    return ("the home found for the mechanism file, which gives none (the assembly mode of "
            "largest margin on the slice of its first joint with most configurations that can "
            "be assembled)")


def kept_scene(scene, bodies):
    """The scene plans and executions keep: the one received, else, with a
    mechanism file's ``bodies``, an empty one, since bodies that share a
    layer must not cross even without obstacles (None: nothing to keep)."""
    if scene is None and bodies is not None:
        return EMPTY_SCENE
    return scene
