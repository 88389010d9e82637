"""The two installs get every package the suite imports, from the right place.

On a stock ROS 2 Jazzy the rosdep keys of the package.xml files bring the
distro's packages and pip adds only what no key provides
(ros2_ws/requirements-system.txt); the declared version ranges run from the
distro's versions (ros2_ws/requirements-floor.txt) to the pins
(ros2_ws/requirements.txt), both of which the test environments install.
"""

import ast
import importlib.metadata
import importlib.util
import pathlib
import sys
import xml.etree.ElementTree as ElementTree

import pytest
from packaging.requirements import Requirement
from packaging.version import Version

ROOT = pathlib.Path(__file__).resolve().parents[1]
WS = ROOT / "ros2_ws"
PACKAGES = {"rpr3_gwr_core": ["rpr3_gwr_core"],
            "rpr3_gwr_msgs": ["test"],
            "rpr3_gwr_nodes": ["rpr3_gwr_nodes", "launch"]}
# What each system-dependency key of the package.xml files installs on
# Ubuntu 24.04: the pip distribution of its apt package and the modules it
# provides (numba's apt package depends on llvmlite's, which the core
# imports too).  The other keys are ROS packages, whose module is their name.
SYSTEM_KEYS = {
    "python3-numpy": ("numpy", {"numpy"}),
    "python3-scipy": ("scipy", {"scipy"}),
    "python3-networkx": ("networkx", {"networkx"}),
    "python3-matplotlib": ("matplotlib", {"matplotlib"}),
    "python3-yaml": ("PyYAML", {"yaml"}),
    "python3-numba": ("numba", {"numba", "llvmlite"}),
    "python3-pytest": ("pytest", {"pytest"}),
    "python3-hypothesis": ("hypothesis", {"hypothesis"}),
    "python3-sphinx": ("Sphinx", {"sphinx"}),
}
# The modules of what requirements-system.txt names.
SYSTEM_PIP_MODULES = {"rosbags": {"rosbags"}, "ruff": set()}
# The ROS packages the wheels lack, built from their published definitions
# where ROS does not install them (setup.sh).
STANDARD_INTERFACES = WS / "standard_interfaces"


def _requirements_module():
    spec = importlib.util.spec_from_file_location("requirements", WS / "requirements.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


requirements = _requirements_module()


def _depends(package, folder=ROOT / "src"):
    """``{key: version_gte or None}`` of a package.xml's dependencies."""
    tree = ElementTree.parse(folder / package / "package.xml")
    return {e.text.strip(): e.get("version_gte") for e in tree.getroot()
            if e.tag.endswith("depend")}


def _imported(package):
    """Top-level names of the modules a package's code imports, outside the
    standard library and itself."""
    names = set()
    for folder in PACKAGES[package]:
        for path in (ROOT / "src" / package / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    names.update(alias.name.split(".")[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    names.add(node.module.split(".")[0])
    return {n for n in names if n not in sys.stdlib_module_names and n != package}


def _pins(path):
    """``{normalized name: Version}`` of a requirements file's ``==`` pins
    that apply to this interpreter."""
    pins = {}
    for name, line in requirements.pins(path):
        requirement = Requirement(line)
        if requirement.marker is None or requirement.marker.evaluate():
            pins[name] = Version(str(requirement.specifier).lstrip("="))
    return pins


def _core_ranges():
    """``{normalized name: SpecifierSet}`` of the core's ``install_requires``."""
    setup = ast.parse((ROOT / "src" / "rpr3_gwr_core" / "setup.py").read_text())
    call = next(n for n in ast.walk(setup) if isinstance(n, ast.Call)
                and getattr(n.func, "id", None) == "setup")
    listed = next(k.value for k in call.keywords if k.arg == "install_requires")
    parsed = [Requirement(ast.literal_eval(item)) for item in listed.elts]
    return {requirements.normalized(r.name): r.specifier for r in parsed}


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_every_import_comes_from_a_key_of_the_package_or_from_pip(package):
    provided = set().union(*SYSTEM_PIP_MODULES.values())
    for key in _depends(package):
        provided |= SYSTEM_KEYS[key][1] if key in SYSTEM_KEYS else {key}
    assert _imported(package) - provided == set()


def test_pip_adds_on_a_ros_install_only_what_no_key_provides():
    listed = {requirements.normalized(n) for n in requirements.names(
        WS / "requirements-system.txt")}
    assert listed == set(SYSTEM_PIP_MODULES)
    keyed = {requirements.normalized(SYSTEM_KEYS[k][0])
             for package in PACKAGES for k in _depends(package) if k in SYSTEM_KEYS}
    assert listed & keyed == set()
    # Each is pinned where the wheel install takes it from.
    assert set(_pins(WS / "requirements.txt")) >= listed


def test_the_package_files_declare_the_floor_as_the_oldest_version():
    # Ubuntu's own version, also where a newer one stands in on some Python.
    floor = {}
    for name, line in requirements.pins(WS / "requirements-floor.txt"):
        version = Version(str(Requirement(line).specifier).lstrip("="))
        floor[name] = min(floor.get(name, version), version)
    for package in PACKAGES:
        for key, oldest in _depends(package).items():
            if key in SYSTEM_KEYS:
                name = requirements.normalized(SYSTEM_KEYS[key][0])
                assert oldest is not None and Version(oldest) == floor[name], key


@pytest.mark.parametrize("floor", [None, "requirements-floor.txt"], ids=["pinned", "floor"])
def test_both_ends_of_the_tested_range_lie_in_the_core_s_declared_range(floor, tmp_path):
    merged = tmp_path / "merged.txt"
    merged.write_text("\n".join(requirements.merge(
        [str(WS / "requirements-ros.txt"), str(WS / "requirements.txt")],
        floor and str(WS / floor))))
    pins = _pins(merged)
    for name, specifier in _core_ranges().items():
        if name != "setuptools":
            assert specifier.contains(pins[name]), (name, str(specifier), str(pins[name]))


def test_a_merge_puts_the_floor_s_pins_in_place_of_the_base_s(tmp_path):
    base = tmp_path / "base.txt"
    base.write_text("# pinned\nnumpy==2.4.6\nPy_YAML==6.0.3  # a comment\nrosbags==0.11.9\n")
    floor = tmp_path / "floor.txt"
    floor.write_text('numpy==1.26.4; python_version < "3.12"\n'
                     'numpy==1.26.5; python_version >= "3.12"\npy-yaml==6.0.1\n')
    assert requirements.merge([str(base)], str(floor)) == [
        "rosbags==0.11.9", 'numpy==1.26.4; python_version < "3.12"',
        'numpy==1.26.5; python_version >= "3.12"', "py-yaml==6.0.1"]


def test_a_floor_pin_of_a_package_the_base_lacks_is_refused(tmp_path):
    base = tmp_path / "base.txt"
    base.write_text("numpy==2.4.6\n")
    floor = tmp_path / "floor.txt"
    floor.write_text("scipy==1.11.4\n")
    with pytest.raises(SystemExit, match="scipy pinned by none"):
        requirements.merge([str(base)], str(floor))


def test_the_installed_constraints_pin_this_interpreter_s_packages():
    constraints = requirements.installed()
    assert f"numpy=={importlib.metadata.version('numpy')}" in constraints
    assert all(Requirement(line).specifier for line in constraints)


def test_the_standard_interfaces_are_keys_that_rosdep_installs_on_a_ros_install():
    built = sorted(path.parent.name for path in STANDARD_INTERFACES.glob("*/package.xml"))
    assert built == ["control_msgs", "tf2_msgs"]
    for name in built:
        tree = ElementTree.parse(STANDARD_INTERFACES / name / "package.xml")
        assert tree.getroot().findtext("name") == name
    # The nodes declare them, so rosdep installs the distro's packages; were
    # they under src/, `rosdep install --from-paths src --ignore-src` would
    # take them for the workspace's own and install nothing.
    assert set(built) <= set(_depends("rpr3_gwr_nodes"))
    in_src = {ElementTree.parse(path).getroot().findtext("name")
              for path in (ROOT / "src").rglob("package.xml")}
    assert in_src & set(built) == set()


def test_the_standard_interfaces_build_on_the_pinned_wheels():
    wheels = set(requirements.names(WS / "requirements-ros.txt"))
    for name in sorted(path.parent.name for path in STANDARD_INTERFACES.glob("*/package.xml")):
        for key in _depends(name, STANDARD_INTERFACES):
            assert requirements.normalized(f"ros-{key}") in wheels, (name, key)
