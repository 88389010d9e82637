"""The shipped RViz configuration shows what the nodes publish: its fixed
frame is the nodes' base frame, each MarkerArray display is on a topic a
node publishes, with that topic's durability, and the TF display is on."""

import pathlib
import re

import yaml
from rpr3_gwr_nodes.profiles import BASE_FRAME

ROOT = pathlib.Path(__file__).resolve().parents[1]
CONFIG = ROOT / "config" / "rviz" / "rpr3_gwr.rviz"
NODES = ROOT / "src" / "rpr3_gwr_nodes" / "rpr3_gwr_nodes"


def _published_markers():
    """MarkerArray topics the nodes create publishers for, and whether latched."""
    found = {}
    for source in NODES.glob("*.py"):
        for topic, qos in re.findall(r'create_publisher\(MarkerArray, "(\w+)", (\w+)\)',
                                     source.read_text()):
            found[f"/{topic}"] = qos == "LATCHED_QOS"
    return found


def test_the_rviz_view_shows_the_robot_its_roadmap_path_and_scene_in_base():
    view = yaml.safe_load(CONFIG.read_text())["Visualization Manager"]
    assert view["Global Options"]["Fixed Frame"] == BASE_FRAME
    displays = view["Displays"]
    assert any(d["Class"] == "rviz_default_plugins/TF" and d["Enabled"] for d in displays)
    markers = {d["Topic"]["Value"]: d["Topic"]["Durability Policy"] for d in displays
               if d["Class"] == "rviz_default_plugins/MarkerArray" and d["Enabled"]}
    published = _published_markers()
    assert set(markers) == set(published) == {"/mechanism_markers", "/scene_markers",
                                              "/planned_path_markers", "/roadmap_markers"}
    for topic, latched in published.items():
        assert markers[topic] == ("Transient Local" if latched else "Volatile"), topic
