"""Hostile and valid arguments to every subcommand of ``rpr3-gwr``.

Whatever the arguments, the tool answers with exit code 0 and JSON on
stdout, or fails with code 1 or 2 and exactly one error: an ``error`` object
on stdout (a plan that cannot be made) or one line on stderr, after the
progress lines of a build that ran for seconds; never a traceback, never a
numpy warning.  The fuzz calls ``main`` in this process;
a broken pipe is tried on the installed console script.  Scene and
mechanism files of any content (bytes that are not UTF-8, YAML nested past
what a parser follows, numbers beyond any float) fail with code 2 and one
line.

Every argument that could start a long build is drawn from pools whose valid
values make small grids ('roadmap' always has a step, of 0.5 or more when
valid, and ranges within [0, 50]), the cached 401 x 401 slice at rho1 = 17,
or the refusals of the grid checks; the full 3-DOF roadmap is only named
where an argument error comes first.
"""

import contextlib
import io
import json
import pathlib
import shutil
import subprocess
import warnings

import pytest
from hypothesis import example, given, settings, strategies as st

from rpr3_gwr_core.io.cli import main

PAPER_START, PAPER_GOAL = ["12", "18", "122.82"], ["10", "25", "-24.24"]
# The same two configurations as poses (B1 and alpha [deg]), on the slice rho1 = 17.
PAPER_START_POSE = ["14.2844098014", "-9.21713820156", "122.818069928"]
PAPER_GOAL_POSE = ["0.329281929849", "16.9968106835", "-24.2435688728"]
# Working modes: the 3-RPR's one, others' and malformed ones ("---" reads as an option).
WORKING_MODE = st.sampled_from(["+++", "=+++", "=---", "---", "+-", "x", "", "=+-+"])
CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"


def _mostly(usual, rare):
    """``usual`` three times in four, else ``rare`` (hypothesis starts from 0:
    ``usual`` is the simpler)."""
    return st.integers(0, 3).flatmap(lambda k: rare if k == 3 else usual)


# Valid three times in four; as legs and steps they make grids of at most
# 101 x 101 cells, or grids the checks refuse.
NUMBER = _mostly(st.sampled_from(["17", "12", "18", "50", "0", "0.5", "5", " 17", "-0"]),
                 st.sampled_from(["-1", "1e-4", "1e-300", "5e-324", "nan", "-nan", "inf",
                                  "-inf", "1e308", "-1e308", "1e7", "abc", "", "0x1p3"]))
# Grid steps of 'roadmap' (its default, 0.125, is a 401 x 401 build).
STEP = _mostly(st.sampled_from(["0.5", "1", "5", "17"]), NUMBER)
# The only valid rho1 of commands that build the default 401 x 401 slice.
SLICE_RHO1 = st.sampled_from(["17", "0", "-1", "nan", "inf", "1e308", "1e7", "abc"])
# Steps of --trace's slices: valid ones make grids of at most 51 x 51 cells.
TRACE_STEP = st.sampled_from(["1", "5", "17", "0", "-1", "1e-4", "nan", "inf", "1e308", "x"])
JUNK = st.sampled_from(["--bogus", "-x", "extra", "--", "--rho1", "-o"])


def _numbers(low, high):
    return st.lists(NUMBER, min_size=low, max_size=high)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Paths the fuzz writes and reads: good ones, a directory, a path under a
    file, a missing folder, files of the kernel that cannot be written, and
    plan files valid, damaged or not JSON at all."""
    root = tmp_path_factory.mktemp("cli-fuzz")
    (root / "folder").mkdir()
    (root / "folder.png").mkdir()
    (root / "a-file").write_text("")
    plan = root / "plan.json"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["plan", "--start", *PAPER_START, "--goal", *PAPER_GOAL,
                     "-o", str(plan)]) == 0
    good = json.loads(plan.read_text())
    plans = {"valid": good}
    for name, step in (("tiny-step", 1e-5), ("coarse-step", 5.0), ("huge-step", 1e308)):
        changed = json.loads(plan.read_text())
        for axis in changed["roadmap"]["grid"]["axes"]:
            axis["step"] = step
        plans[name] = changed
    huge = json.loads(plan.read_text())
    huge["roadmap"]["grid"]["fixed"][0]["value"] = 1e308
    plans["huge-rho1"] = huge
    plans["full"] = dict(good, roadmap={"full": True})
    plans["failed"] = dict(good, feasible=False, error={"code": "INFEASIBLE", "message": "no"})
    plans["no-waypoints"] = dict(good, waypoints=[])
    plans["bad-waypoints"] = dict(good, waypoints=[{"joints": [1, 2], "pose": "x"}])
    plans["bad-path"] = dict(good, global_paths=[["a"]], path_index=0)
    plans["bad-index"] = dict(good, path_index=7)
    plans["bad-mechanism"] = dict(good, roadmap={"mechanism": dict(good["roadmap"]["mechanism"],
                                                                   d1=-1.0),
                                                 "grid": good["roadmap"]["grid"]})
    plans["bad-kind"] = dict(good, roadmap={"mechanism": {"kind": "delta"},
                                            "grid": good["roadmap"]["grid"]})
    for name, document in plans.items():
        (root / f"{name}.plan").write_text(json.dumps(document))
    for name, text in (("empty", ""), ("list", "[]"), ("object", "{}"), ("number", "1e999"),
                       ("truncated", plan.read_text()[:200]), ("roadmap-list", '{"roadmap": []}'),
                       ("nan-grid", '{"roadmap": {"mechanism": {}, "grid": NaN}}')):
        (root / f"{name}.plan").write_text(text)
    (root / "binary.plan").write_bytes(b"\xff\xfe\x00garbage")
    return root


def _run(argv):
    """``main(argv)`` with its streams captured: exit code, stdout, stderr.
    An exception out of ``main``, a traceback in a shell, fails the test as
    it is."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        # An overflow or invalid value on the way is a failure, not a result.
        warnings.simplefilter("error", RuntimeWarning)
        try:
            code = main(argv)
        except SystemExit as stop:
            code = stop.code
    return code, out.getvalue(), err.getvalue()


def _strict_json(text):
    def refuse(constant):
        raise AssertionError(f"{constant} in the JSON output")
    return json.loads(text, parse_constant=refuse)


def _without_progress(err):
    """stderr without the progress lines of a build that ran for seconds."""
    return "".join(line for line in err.splitlines(keepends=True)
                   if not line.startswith("rpr3-gwr: ["))


def _check(argv):
    """Check the answer to ``argv``; its exit code, stdout and stderr."""
    code, out, err = _run(argv)
    assert "Traceback" not in err, (argv, err)
    err = _without_progress(err)
    assert code in (0, 1, 2), (argv, code, err)
    if code == 0:
        _strict_json(out)
    elif out:
        document = _strict_json(out)
        assert set(document["error"]) == {"code", "message"} and err == "", (argv, out, err)
    else:
        assert err.startswith("rpr3-gwr") and ": error: " in err, (argv, err)
        assert err.count("\n") == 1 and err.endswith("\n"), (argv, err)
    return code, out, err


def _out_file(files):
    return _mostly(st.just(files / "out.json"),
                   st.sampled_from([files / "folder", files / "a-file" / "x",
                                    files / "missing" / "x.json", "/proc/version", "/dev/full"]))


def _figure_file(files):
    return _mostly(st.sampled_from([files / "f.png", files / "f.svg"]),
                   st.sampled_from([files / "f.xyz", files / "f.", files / "folder.png",
                                    files / "a-file" / "x.png", files / "missing" / "f.pdf",
                                    "/proc/version"]))


@st.composite
def _options(draw, table, required=()):
    """Some of ``table``'s options (each one time in five, all of
    ``required``), in any order, sometimes with a stray argument."""
    names = [n for n in table if n in required or draw(st.integers(0, 4)) == 4]
    names = draw(st.permutations(names))
    argv = []
    for name in names:
        value = draw(table[name])
        argv += [name] + [str(v) for v in (value if isinstance(value, list) else [value])]
    return argv + (draw(st.lists(JUNK, max_size=1)) if draw(st.integers(0, 4)) == 4 else [])


def _dk():
    return _mostly(_numbers(3, 3), _numbers(0, 4)).map(lambda numbers: ["dk", *numbers])


def _ik():
    files = st.sampled_from([[]] + [["--mechanism", str(CONFIG / name)] for name in
                                    ("five_bar.yaml", "three_rrr.yaml", "three_prr.yaml")])
    return st.tuples(_mostly(_numbers(3, 3), _numbers(0, 4)), files).map(
        lambda case: ["ik", *case[1], *case[0]])


def _roadmap(files):
    figure = _figure_file(files)
    options = _options({
        "--rho1": NUMBER, "--rho2": _mostly(_numbers(2, 2), _numbers(1, 3)),
        "--rho3": _mostly(_numbers(2, 2), _numbers(1, 3)),
        "--step": STEP, "--method": st.sampled_from(["components", "rds", "bogus"]),
        "-o": _out_file(files), "--gexf": _out_file(files), "--field-figure": figure,
        "--roadmap-figure": figure, "--slice-figure": figure, "--slice-rho1": NUMBER},
        required=("--step",))
    # --full alone would build the full roadmap: only with its argument error.
    full = figure.map(lambda path: ["--full", "--field-figure", str(path)])
    return st.integers(0, 5).flatmap(lambda k: full if k == 5 else options).map(
        lambda argv: ["roadmap", *argv])


@st.composite
def _plan(draw, files):
    legs = _mostly(st.one_of(st.sampled_from([PAPER_START, PAPER_GOAL]), _numbers(3, 3)),
                   _numbers(0, 5))
    poses = _mostly(st.sampled_from([PAPER_START_POSE, PAPER_GOAL_POSE]), _numbers(0, 4))
    start, goal = draw(legs), draw(legs)
    # Each end as joints or as a pose, sometimes both (refused).
    ends = [draw(st.sampled_from([(f"--{end}",), (f"--{end}",), (f"--{end}-pose",),
                                  (f"--{end}", f"--{end}-pose")])) for end in ("start", "goal")]
    modes = {f"--{end}-working-mode": WORKING_MODE for end in ("start", "goal")}
    argv = draw(_options({
        "--rho1": SLICE_RHO1, "--start": st.just(start), "--goal": st.just(goal),
        "--start-pose": poses, "--goal-pose": poses, **modes,
        "--smooth": st.just([]), "--no-smooth": st.just([]), "--weighted": st.just([]),
        "--feasibility-only": st.just([]),
        "--max-velocity": _mostly(st.tuples(NUMBER, NUMBER).map(
            lambda limits: [limits[0], "--max-acceleration", limits[1]]), NUMBER),
        "--joint-limit": st.tuples(st.sampled_from(["rho1", "rho2", "rho3", "th1", "", "rho2="]),
                                   NUMBER, NUMBER).map(
            lambda limit: [f"{limit[0]}={limit[1]},{limit[2]}"]),
        "--alpha-tol-deg": NUMBER, "--clearance": NUMBER,
        "-o": _out_file(files)}, required=ends[0] + ends[1]))
    # A working mode drawn as "=SIGNS" is written --option=SIGNS.
    written = []
    for arg in argv:
        if arg.startswith("=") and written and written[-1].endswith("-working-mode"):
            written[-1] += arg
        else:
            written.append(arg)
    argv = written
    # --full with four legs in both would build the full roadmap.
    if (len(start), len(goal)) != (4, 4) and draw(st.integers(0, 5)) == 5:
        argv.append("--full")
    return ["plan", *argv]


def _plot(files):
    plans = sorted(str(p) for p in files.glob("*.plan")) + [
        str(files / "missing.json"), str(files / "folder"), "/proc/version"]
    options = _options({"-o": _figure_file(files)})
    plan = st.one_of(st.just(str(files / "plan.json")), st.sampled_from(plans))
    return st.tuples(plan, options).map(
        lambda case: ["plot", case[0], *case[1]])


def _cusps():
    ends = st.sampled_from(["12", "17", "18", "0", "-1", "nan", "inf", "1e308", "abc", "1e-4",
                            "5"])
    trace = st.tuples(_mostly(st.lists(ends, min_size=3, max_size=3),
                              st.lists(ends, min_size=2, max_size=4)), TRACE_STEP).map(
        lambda case: ["--trace", *case[0], "--step", case[1]])
    plain = _options({"--rho1": SLICE_RHO1})
    return st.one_of(trace, plain).map(lambda argv: ["cusps", *argv])


@pytest.mark.slow
@settings(max_examples=150, deadline=None, database=None)
@given(argv=_dk())
@example(argv=["dk", "1e308", "1e308", "1e308"])
@example(argv=["dk", "17", "20", "25"])
def test_dk_answers_json_or_one_error(argv):
    _check(argv)


@pytest.mark.slow
@settings(max_examples=60, deadline=None, database=None)
@given(data=st.data())
@example(data=["roadmap", "--rho1", "1e308"])
@example(data=["roadmap", "--rho2", "0", "1e308"])
@example(data=["roadmap", "--step", "1e-4"])
@example(data=["roadmap", "--field-figure", "f.xyz"])
@example(data=["roadmap", "--rho2", "0", "0"])
@example(data=["roadmap", "--rho1", "100", "--step", "1"])
@example(data=["roadmap", "--step", "2", "-o", "/proc/version"])
def test_roadmap_answers_json_or_one_error(data, files):
    _check(data if isinstance(data, list) else data.draw(_roadmap(files)))


@pytest.mark.slow
@settings(max_examples=100, deadline=None, database=None)
@given(argv=_ik())
@example(argv=["ik", "1e308", "1e308", "1e308"])
@example(argv=["ik", "--mechanism", str(CONFIG / "five_bar.yaml"), "0.5", "0.5"])
def test_ik_answers_json_or_one_error(argv):
    _check(argv)


@pytest.mark.slow
@settings(max_examples=100, deadline=None, database=None)
@given(data=st.data())
@example(data=["plan", "--start-pose", *PAPER_START_POSE, "--goal-pose", *PAPER_GOAL_POSE])
@example(data=["plan", "--start-pose", *PAPER_START_POSE, "--goal", *PAPER_GOAL,
               "--start-working-mode=+-+"])
@example(data=["plan", "--rho1", "1e308", "--start", *PAPER_START, "--goal", *PAPER_GOAL])
@example(data=["plan", "--start", *PAPER_START, "--goal", *PAPER_GOAL, "--smooth"])
def test_plan_answers_json_or_one_error(data, files):
    _check(data if isinstance(data, list) else data.draw(_plan(files)))


@pytest.mark.slow
@settings(max_examples=40, deadline=None, database=None)
@given(data=st.data())
def test_plot_answers_json_or_one_error(data, files):
    _check(data.draw(_plot(files)))


@pytest.mark.slow
@settings(max_examples=30, deadline=None, database=None)
@given(data=st.data())
@example(data=["cusps", "--trace", "12", "18", "1", "--step", "1e308"])
def test_cusps_answers_json_or_one_error(data):
    _check(data if isinstance(data, list) else data.draw(_cusps()))


def _nested(depth):
    return st.sampled_from([b"[" * depth + b"]" * depth, b"- " * depth + b"x\n",
                            b"{a: " * depth + b"1" + b"}" * depth])


def _huge_numbers(text):
    """``text`` without its comments, one of its numbers made huge: digits
    beyond any float, a float near its largest, or YAML 1.2's 1e300."""
    text = "".join(line for line in text.splitlines(keepends=True)
                   if not line.lstrip().startswith("#"))
    numbers = sorted({word.strip("[],{}") for word in text.split()
                      if word.strip("[],{}").replace(".", "", 1).isdigit()})
    huge = st.sampled_from(["9" * 400, "-" + "9" * 400, "9" * 5000, "1.0e+200", "-1.0e+200",
                            "1e300", "1.7e+308"])
    return st.tuples(st.sampled_from(numbers), huge).map(
        lambda swap: text.replace(swap[0], swap[1], 1).encode())


def _invalid_file(text):
    """Contents that are never a valid file: ``text`` in another encoding,
    with a number beyond range, or YAML nested deeply."""
    return st.one_of(
        st.sampled_from(["utf-16", "utf-16-le", "utf-32"]).map(text.encode),
        st.just((text + "# caf\xe9\n").encode("latin-1")),
        st.binary(max_size=200).map(lambda junk: b"\xff" + junk),
        st.integers(1, 60_000).flatmap(_nested),
        _huge_numbers(text))


SCENE_TEXT = "obstacles:\n  - {id: post, disc: {center: [6.0, 28.0], radius: 2.0}}\n" \
    "  - {id: plate, polygon: [[-20, 24], [-12, 24], [-12, 30], [-20, 30]]}\n" \
    "limits: {obstacle_clearance: 0.5}\n"


def _file_argv(files, content, argv):
    path = files / "hostile.yaml"
    path.write_bytes(content)
    return [str(path) if word == "FILE" else word for word in argv]


@pytest.mark.slow
@settings(max_examples=60, deadline=None, database=None)
@given(content=st.one_of(_invalid_file(SCENE_TEXT), st.binary(max_size=300)))
def test_a_scene_file_of_any_content_answers_json_or_one_error(content, files):
    code, _, err = _check(_file_argv(files, content, ["roadmap", "--step", "5",
                                                      "--scene", "FILE"]))
    if content.startswith(b"\xff") or b"[[[" in content or b"9" * 300 in content:
        assert code == 2, err


@pytest.mark.slow
@settings(max_examples=60, deadline=None, database=None)
@given(content=st.one_of(_invalid_file((CONFIG / "paper_3rpr.yaml").read_text()),
                         st.binary(max_size=300)))
def test_a_mechanism_file_of_any_content_answers_json_or_one_error(content, files):
    code, _, err = _check(_file_argv(files, content, ["dk", "--mechanism", "FILE", "17", "20",
                                                      "25"]))
    if content.startswith(b"\xff") or b"[[[" in content or b"9" * 300 in content:
        assert code == 2, err


@pytest.fixture(scope="module")
def console_script():
    script = shutil.which("rpr3-gwr")
    if script is None:
        pytest.skip("the rpr3-gwr console script is not installed (source ros2_ws/env.sh)")
    return script


@pytest.mark.parametrize("argv", [["cusps"], ["dk", "17", "20", "25"]])
def test_a_reader_that_leaves_early_ends_the_tool_quietly(argv, console_script):
    # The read end is closed before the tool writes, as ``| head -c 10``
    # does once it has its bytes.
    tool = subprocess.Popen([console_script, *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE)
    try:
        tool.stdout.close()
        _, err = tool.communicate(timeout=120)
    finally:
        tool.kill()
        tool.wait()
    assert tool.returncode == 1
    # Nothing but the progress of a build that took seconds (a cold cache).
    assert _without_progress(err.decode()) == ""


@pytest.mark.parametrize("argv, reason", [
    (["dk", "1e308", "1e308", "1e308"], "out of range"),
    (["roadmap", "--step", "1e-4"], "exceeds the limit of 4000000"),
])
def test_the_console_script_fails_with_one_line(argv, reason, console_script):
    done = subprocess.run([console_script, *argv], capture_output=True, text=True, timeout=120,
                          check=False)
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.count("\n") == 1 and reason in done.stderr


@pytest.mark.parametrize("argv, code", [(["dk", "17", "20", "25"], 0), (["--help"], 0),
                                        (["dk", "17", "20", "-3"], 2)])
def test_the_console_script_ends_with_its_whole_answer(argv, code, console_script):
    # It ends with os._exit once its answer is flushed: the answer must be
    # whole and the exit code the command's.
    done = subprocess.run([console_script, *argv], capture_output=True, text=True, timeout=120,
                          check=False)
    assert done.returncode == code
    if argv[0] == "dk" and code == 0:
        assert len(json.loads(done.stdout)) == 4 and done.stderr == ""
    elif code == 0:
        assert done.stdout.startswith("usage: rpr3-gwr")
    else:
        assert done.stdout == "" and done.stderr.count("\n") == 1
