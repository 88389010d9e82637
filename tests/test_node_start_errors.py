"""A node that cannot start says why in one error line and exits with status
1, without a traceback: the builder, the planner and the driver given a
mechanism file that is missing, not text, or not a mechanism, and a
parameter of the wrong type.  Real processes on the test run's ROS domain
and loopback DDS profile."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
LIB = ROOT / "ros2_ws" / "install" / "rpr3_gwr_nodes" / "lib" / "rpr3_gwr_nodes"
TIMEOUT = 60.0


def _files(folder):
    (folder / "bytes.yaml").write_bytes(bytes(range(256)) * 4)
    (folder / "geometry.yaml").write_text("mechanism: {kind: 3-RPR, d_3: 1}\njoints: []\n")
    return {"missing": (folder / "missing.yaml", "missing.yaml"),
            "bytes": (folder / "bytes.yaml", "bytes.yaml"),
            "geometry": (folder / "geometry.yaml", "geometry.yaml")}


@pytest.mark.parametrize("executable", ["roadmap_builder", "planner", "rpr3_driver"])
@pytest.mark.parametrize("case", ["missing", "bytes", "geometry"])
def test_a_node_given_a_bad_mechanism_file_exits_with_one_line(executable, case, tmp_path):
    path, named = _files(tmp_path)[case]
    done = subprocess.run([str(LIB / executable), "--ros-args", "-p", f"mechanism_file:={path}"],
                          env=os.environ.copy(), capture_output=True, text=True,
                          timeout=TIMEOUT)
    output = done.stdout + done.stderr
    assert done.returncode == 1, output
    assert "Traceback" not in output, output
    errors = [line for line in output.splitlines() if "[ERROR]" in line]
    assert len(errors) == 1 and "cannot start: " in errors[0] and named in errors[0], output


def test_a_parameter_of_the_wrong_type_is_one_line_too():
    done = subprocess.run([str(LIB / "roadmap_builder"), "--ros-args", "-p", "full:=maybe"],
                          env=os.environ.copy(), capture_output=True, text=True,
                          timeout=TIMEOUT)
    output = done.stdout + done.stderr
    assert done.returncode == 1 and "Traceback" not in output, output
    assert "cannot start: " in output and "full" in output, output
