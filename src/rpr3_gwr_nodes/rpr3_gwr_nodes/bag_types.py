"""The message types bags of the suite are written and read with: ROS 2
Jazzy's standard types and the suite's own, from the installed
rpr3_gwr_msgs definitions (the ``rosbags`` library knows only the former)."""

import pathlib

from ament_index_python.packages import get_package_share_directory
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

__all__ = ["suite_typestore"]


def suite_typestore():
    """A ``rosbags`` type store of Jazzy's types and rpr3_gwr_msgs's."""
    typestore = get_typestore(Stores.ROS2_JAZZY)
    folder = pathlib.Path(get_package_share_directory("rpr3_gwr_msgs")) / "msg"
    types = {}
    for path in sorted(folder.glob("*.msg")):
        types.update(get_types_from_msg(path.read_text(encoding="utf-8"),
                                        f"rpr3_gwr_msgs/msg/{path.stem}"))
    typestore.register(types)
    return typestore
