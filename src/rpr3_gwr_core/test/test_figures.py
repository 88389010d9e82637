"""The figures: each is written as a readable PNG and shows what explains it
(count colour bars, region ids, legends, both global paths, start and goal,
the joints and pose track of plans off a 2-D grid, the base plane of plans in
a scene), for the paper's slice, 3-D roadmaps (uniform, adaptive, the full
one) and other mechanisms."""

import math
import pathlib

import matplotlib.image
import numpy as np
import pytest
from matplotlib.patches import Circle, Polygon

from rpr3_gwr_core import PAPER_GEOMETRY, Grid, Planner, build_roadmap
from rpr3_gwr_core.exceptions import GWRError, InvalidInputError
from rpr3_gwr_core.figures import field_figure, plan_figure, roadmap_figure, slice_figure
from rpr3_gwr_core.io.mechanism_file import load_mechanism_file
from rpr3_gwr_core.mechanisms import DEFAULT_FIVE_BAR
from rpr3_gwr_core.workspace.adaptive import coarse_base, refine
from rpr3_gwr_core.workspace.cusps import find_cusps
from rpr3_gwr_core.workspace.grid import Axis
from rpr3_gwr_core.io.scene_file import load_scene
from rpr3_gwr_core.world import EMPTY_SCENE

D = math.radians
Q1, Q2 = (17, 12, 18, D(122.82)), (17, 10, 25, D(-24.24))
MODE_A, MODE_B = (17, 20, 25, D(29.47)), (17, 20, 25, D(96.13))
CONFIG = pathlib.Path(__file__).resolve().parents[3] / "config"


@pytest.fixture(scope="module")
def planes_roadmap():
    """A 3-D roadmap whose rho1 = 17 plane is the coarse paper roadmap's grid."""
    return build_roadmap(PAPER_GEOMETRY, Grid.regular(
        {0: (16.0, 18.0), 1: (0.0, 50.0), 2: (0.0, 50.0)}, 0.5))


@pytest.fixture(scope="module")
def adaptive_roadmap():
    """A small refined 3-D roadmap over all three legs."""
    base = Grid.regular({0: (12.0, 20.0), 1: (10.0, 18.0), 2: (16.0, 24.0)}, 1.0)
    return build_roadmap(PAPER_GEOMETRY, refine(PAPER_GEOMETRY, base, 4))


@pytest.fixture(scope="module")
def five_bar_torus():
    step = 2 * math.pi / 120
    return build_roadmap(DEFAULT_FIVE_BAR, Grid(axes=tuple(
        Axis(j, -math.pi, math.pi - step, step, periodic=True) for j in (0, 1))))


@pytest.fixture(scope="module")
def rrr_torus():
    mechanism = load_mechanism_file(CONFIG / "three_rrr.yaml").mechanism
    step = 2 * math.pi / 24
    fine = Grid(axes=tuple(Axis(j, -math.pi, math.pi - step, step, periodic=True)
                           for j in range(3)))
    return build_roadmap(mechanism, refine(mechanism, coarse_base(fine, 2), 2))


@pytest.fixture(scope="module")
def rrr_slice():
    """The 3-RRR's slice th1 = 0: a torus of th2, th3, 120 cells a turn."""
    described = load_mechanism_file(CONFIG / "three_rrr.yaml")
    return build_roadmap(described.mechanism, described.grid({"th1": 0.0}))


def written(figure, tmp_path):
    """Saves a figure as PNG and reads it back: its pixels."""
    path = tmp_path / "figure.png"
    figure.savefig(path, dpi=60)
    assert path.stat().st_size > 0
    pixels = matplotlib.image.imread(path)
    assert pixels.ndim == 3 and min(pixels.shape[:2]) > 100
    return pixels


def region_labels(ax):
    """Region id -> (position, circle colour) of the circled ids of an axes."""
    return {t.get_text(): (tuple(np.round(t.get_position(), 6)),
                           tuple(np.round(t.get_bbox_patch().get_facecolor(), 6)))
            for t in ax.texts if t.get_bbox_patch() is not None and t.get_text().isdigit()}


def legend_texts(legend):
    return [t.get_text() for t in legend.get_texts()]


def legend_handles(legend):
    """The legend's handles in the order of its texts: ``legend_handles``
    from matplotlib 3.7 on, ``legendHandles`` in 3.6, the oldest supported."""
    if hasattr(legend, "legend_handles"):
        return legend.legend_handles
    return legend.legendHandles


def captions(figure):
    return " ".join(t.get_text() for t in figure.texts)


def assert_integer_count_bar(figure, max_solutions):
    bars = [ax for ax in figure.axes if ax.get_label() == "<colorbar>"]
    assert len(bars) == 1
    ticks = [t.get_text() for t in bars[0].get_yticklabels()]
    assert ticks == [str(n) for n in range(max_solutions + 1)]
    assert bars[0].get_ylabel() == "direct-kinematic solutions per cell"


def planned(roadmap, start, goal):
    return Planner(roadmap).plan(start, goal).to_dict()


def plan_in_one_patch(roadmap, seed=0):
    """A plan between two well-conditioned solutions of the largest patch."""
    seg, field = roadmap.segmentation, roadmap.field
    mode = roadmap.mechanism.mode_coordinate
    patch = max(seg.patches.values(), key=lambda p: p.cells.size)
    clear = np.abs(field.margin[patch.cells, patch.slots]) > 0.05
    cells, slots = patch.cells[clear], patch.slots[clear]
    rng = np.random.default_rng(seed)
    for _ in range(20):
        a, b = rng.choice(cells.size, 2, replace=False)
        ends = [(*roadmap.grid.joints_of(cells[k]), field.poses[cells[k], slots[k], mode])
                for k in (a, b)]
        try:
            return planned(roadmap, *ends)
        except GWRError:  # an end too near a singularity to locate: draw others
            continue
    raise AssertionError("no plan in the largest patch")


def test_field_figure_has_a_count_bar_region_ids_and_the_patch_id_rule(coarse_paper_roadmap,
                                                                        tmp_path):
    figure = field_figure(coarse_paper_roadmap)
    written(figure, tmp_path)
    seg = coarse_paper_roadmap.segmentation
    assert set(region_labels(figure.axes[0])) == {str(r) for r in range(1, seg.n_regions + 1)}
    assert_integer_count_bar(figure, seg.field.max_solutions)
    assert {"cusp", "region boundary"} <= set(legend_texts(figure.axes[0].get_legend()))
    assert "Patch id = 10 x region + layer" in captions(figure)
    assert figure.axes[0].get_xlabel() == "rho2 [length]"
    assert "rho1 = 17" in figure.axes[0].get_title()


def test_the_field_figure_hatches_what_a_scene_blocks(coarse_paper_roadmap, tmp_path):
    world = Planner(coarse_paper_roadmap).apply_scene(
        load_scene(CONFIG / "scenes" / "paper_example1_blocked.yaml"))
    figure = field_figure(coarse_paper_roadmap, world)
    written(figure, tmp_path)
    legend = figure.axes[0].get_legend()
    hatches = {t.get_text(): h.get_hatch() for t, h in zip(legend.get_texts(),
                                                           legend_handles(legend))
               if t.get_text().startswith("scene")}
    assert hatches["scene blocks some solutions"] == "//"
    assert f"{world.n_parts} free parts in the scene" in figure.axes[0].get_title()


def test_the_slice_of_a_3d_roadmap_numbers_and_colours_regions_as_the_2d_field(
        coarse_paper_roadmap, planes_roadmap, tmp_path):
    flat = field_figure(coarse_paper_roadmap)
    cut = slice_figure(planes_roadmap, {0: 17.0})
    written(cut, tmp_path)
    assert region_labels(cut.axes[0]) == region_labels(flat.axes[0])
    assert len(region_labels(cut.axes[0])) == coarse_paper_roadmap.segmentation.n_regions
    assert_integer_count_bar(cut, PAPER_GEOMETRY.max_solutions)
    # Beside each plane id, the 3-D roadmap's own region.
    inside = [t.get_text() for t in cut.axes[0].texts if t.get_text().startswith("in ")]
    assert len(inside) == len(region_labels(cut.axes[0]))
    assert {int(t[3:]) for t in inside} <= set(range(1, planes_roadmap.segmentation.n_regions + 1))
    assert "slice rho1 = 17 of the 3-D roadmap" in cut.axes[0].get_title()


def test_a_2d_roadmap_drawn_as_a_slice_keeps_its_own_region_ids(coarse_paper_roadmap):
    """The slice's own numbering of a plane is the segmentation's."""
    assert region_labels(slice_figure(coarse_paper_roadmap, {}).axes[0]) == region_labels(
        field_figure(coarse_paper_roadmap).axes[0])


def test_roadmap_figure_names_patches_regions_and_aspects(coarse_paper_roadmap, tmp_path):
    figure = roadmap_figure(coarse_paper_roadmap)
    written(figure, tmp_path)
    seg = coarse_paper_roadmap.segmentation
    texts = {t.get_text() for t in figure.axes[0].texts}
    assert {str(p) for p in seg.patches} <= texts
    legend = legend_texts(figure.axes[0].get_legend())
    assert {"positive aspect", "negative aspect"} <= set(legend)
    assert {f"region {r}" for r in range(1, seg.n_regions + 1)} <= set(legend)
    assert "Patch id = 10 x region + layer" in captions(figure)


def test_a_region_has_one_colour_in_every_figure(coarse_paper_roadmap):
    field_colours = {int(k): c for k, (_, c) in region_labels(
        field_figure(coarse_paper_roadmap).axes[0]).items()}
    legend = roadmap_figure(coarse_paper_roadmap).axes[0].get_legend()
    roadmap_colours = {int(t.get_text().split()[1]): tuple(np.round(h.get_facecolor(), 6))
                       for t, h in zip(legend.get_texts(), legend_handles(legend))
                       if t.get_text().startswith("region")}
    assert field_colours == roadmap_colours
    plan = plan_figure(coarse_paper_roadmap, planned(coarse_paper_roadmap, Q1, Q2))
    plan_colours = {int(k): c for k, (_, c) in region_labels(plan.axes[0]).items()}
    assert plan_colours == field_colours


def test_a_plan_figure_draws_both_global_paths(coarse_paper_roadmap, tmp_path):
    plan = planned(coarse_paper_roadmap, Q1, Q2)
    assert len(plan["global_paths"]) == 2
    figure = plan_figure(coarse_paper_roadmap, plan)
    written(figure, tmp_path)
    for ax in figure.axes[:2]:
        styles = [line.get_linestyle() for line in ax.get_lines()
                  if line.get_color() in ("tab:orange", "tab:purple")]
        assert sorted(styles) == ["-", "--"]
    paths = [t for t in legend_texts(figure.axes[0].get_legend()) if t.startswith("global path")]
    chosen = plan["path_index"] + 1
    assert len(paths) == 2 and f"global path {chosen} (chosen): 64 > 56 > 24 > 12" in paths
    assert figure.axes[1].get_zlabel() == "alpha [deg]"


def test_start_and_goal_show_apart_where_they_share_the_legs(coarse_paper_roadmap):
    figure = plan_figure(coarse_paper_roadmap, planned(coarse_paper_roadmap, MODE_A, MODE_B))
    ax = figure.axes[0]
    ends = {line.get_label().split()[0]: line for line in ax.get_lines()
            if line.get_label().startswith(("start", "goal"))}
    assert ends["start"].get_marker() != ends["goal"].get_marker()
    assert np.allclose(ends["start"].get_xydata(), ends["goal"].get_xydata())
    labels = {t.get_text() for t in ax.texts}
    assert {"start (alpha = 29.5 deg)", "goal (alpha = 96.1 deg)"} <= labels
    positions = [t.xyann for t in ax.texts if t.get_text().startswith(("start", "goal"))]
    assert positions[0] != positions[1]


def drawn_global_path(ax, k):
    """The line of the k-th global path (from 0) in a plan figure's axes."""
    lines = [line for line in ax.get_lines() if line.get_gid() == f"global path {k + 1}"]
    assert len(lines) == 1
    return lines[0]


def test_global_paths_are_drawn_through_cells_of_their_patches(coarse_paper_roadmap):
    roadmap = coarse_paper_roadmap
    seg, grid = roadmap.segmentation, roadmap.grid
    plan = planned(roadmap, Q1, Q2)
    figure = plan_figure(roadmap, plan)
    for k, path in enumerate(plan["global_paths"]):
        cells = np.concatenate([seg.patches[p].cells for p in path])
        vertices = drawn_global_path(figure.axes[0], k).get_xydata()
        assert np.isin(grid.cells_of(vertices), cells).all()


def test_the_planned_global_path_is_drawn_along_the_waypoints(coarse_paper_roadmap):
    plan = planned(coarse_paper_roadmap, Q1, Q2)
    figure = plan_figure(coarse_paper_roadmap, plan)
    waypoints = np.array([w["joints"][1:] for w in plan["waypoints"]])
    assert np.array_equal(drawn_global_path(figure.axes[0], plan["path_index"]).get_xydata(),
                          waypoints)


def test_another_global_path_crosses_its_gates_in_order_and_stays_in_its_patches(
        coarse_paper_roadmap):
    """Every segment of a global path that was not planned stays in cells of
    its patches, and its vertices go from the start's patch to the goal's
    through the path's patches in order, each step to the same patch or
    across a face of their gate."""
    roadmap = coarse_paper_roadmap
    seg, grid = roadmap.segmentation, roadmap.grid
    plan = planned(roadmap, Q1, Q2)
    k = 1 - plan["path_index"]
    path = plan["global_paths"][k]
    vertices = drawn_global_path(plan_figure(roadmap, plan).axes[0], k).get_xydata()
    cells = np.concatenate([seg.patches[p].cells for p in path])
    t = np.linspace(0.0, 1.0, 400)[:, None]
    for a, b in zip(vertices[:-1], vertices[1:]):
        assert np.isin(grid.cells_of(a + t * (b - a)), cells).all()
    # The patch of each vertex: the first of the path's patches at or after the last one.
    at, layers = 0, []
    for cell in grid.cells_of(vertices):
        mine = [n for n, p in enumerate(path) if n >= at and p in seg.patch[cell]]
        assert mine
        at = mine[0]
        layers.append(at)
    assert layers[0] == 0 and layers[-1] == len(path) - 1
    assert set(np.diff(layers)) <= {0, 1}
    for n in np.flatnonzero(np.diff(layers)):
        pair = grid.cells_of(vertices[n:n + 2])
        gate = seg.gates[tuple(sorted(path[layers[n]:layers[n] + 2]))]
        assert any(set(face) == set(pair) for face in gate.faces.tolist())


def plan_across_the_seam(roadmap):
    """A plan in one patch of the 3-RRR's slice from 8 cells before the seam
    of th2 to 8 cells after it: the clearest such pair of solutions."""
    seg, field, grid = roadmap.segmentation, roadmap.field, roadmap.grid
    n = grid.axes[0].count
    best = None
    for j in range(grid.axes[1].count):
        a, b = (int(np.ravel_multi_index((i, j), grid.shape)) for i in (n - 8, 7))
        for i in range(field.count[a]):
            for k in np.flatnonzero(seg.patch[b, :field.count[b]] == seg.patch[a, i]):
                clear = min(abs(field.margin[a, i]), abs(field.margin[b, k]))
                if seg.patch[a, i] > 0 and (best is None or clear > best[0]):
                    best = (clear, a, i, b, k)
    _, a, i, b, k = best
    mode = roadmap.mechanism.mode_coordinate
    return planned(roadmap, (*grid.joints_of(a), field.poses[a, i, mode]),
                   (*grid.joints_of(b), field.poses[b, k, mode]))


def turns_apart(x, y):
    """Whether two points in degrees differ by whole turns."""
    offset = np.asarray(x) - np.asarray(y)
    return np.allclose(offset - 360.0 * np.round(offset / 360.0), 0.0, atol=1e-9)


def test_a_trajectory_across_the_seam_is_drawn_on_from_its_start_to_its_goal(rrr_slice):
    plan = plan_across_the_seam(rrr_slice)
    joints = np.degrees([w["joints"][1:] for w in plan["waypoints"]])
    # th2 crosses its seam at +-180 deg: a short move, across the ends of its turn.
    wrapped = np.mod(joints + 180.0, 360.0) - 180.0
    assert np.ptp(np.degrees(rrr_slice.grid.unwrap(
        [w["joints"] for w in plan["waypoints"]])[:, 1])) < 180.0 < np.ptp(wrapped[:, 0])
    figure = plan_figure(rrr_slice, plan)
    for ax in figure.axes[:2]:
        lines = [line for line in ax.get_lines() if line.get_gid() == "trajectory"]
        assert len(lines) == 1
        drawn = np.array(lines[0].get_data_3d() if ax.name == "3d"
                         else lines[0].get_xydata().T).T[:, :2]
        assert turns_apart(drawn[0], joints[0]) and turns_apart(drawn[-1], joints[-1])
        steps = np.diff(drawn, axis=0)
        steps = steps[np.all(np.isfinite(steps), axis=1)]
        assert np.all(np.abs(steps) <= 180.0)
        # Nothing left out: the pieces drawn are as long as the path.
        length = np.linalg.norm(np.diff(np.degrees(rrr_slice.grid.unwrap(
            [w["joints"] for w in plan["waypoints"]]))[:, 1:], axis=0), axis=1).sum()
        assert np.linalg.norm(steps, axis=1).sum() == pytest.approx(length)
    # The start and goal marks sit on the drawn line.
    ax = figure.axes[0]
    drawn = [line for line in ax.get_lines() if line.get_gid() == "trajectory"][0].get_xydata()
    for end in ("start", "goal"):
        mark = [line for line in ax.get_lines() if line.get_label().startswith(end)][0]
        assert np.nanmin(np.linalg.norm(drawn - mark.get_xydata()[0], axis=1)) < 1e-9


def test_a_plan_figure_on_a_slice_marks_its_cusps(coarse_paper_roadmap):
    cusps = find_cusps(coarse_paper_roadmap)
    assert cusps
    figure = plan_figure(coarse_paper_roadmap, planned(coarse_paper_roadmap, MODE_A, MODE_B))
    ax = figure.axes[0]
    assert "cusp" in legend_texts(ax.get_legend())
    marks = [line for line in ax.get_lines() if line.get_label() == "cusp"]
    assert len(marks) == 1
    assert np.allclose(marks[0].get_xydata(), [c.joints[1:] for c in cusps])
    assert marks[0].get_marker() == "^"


def test_a_global_path_not_planned_is_drawn_across_the_seam_the_short_way(rrr_slice):
    """The seam plan's patch drawn as a second global path, along cells of
    the patch: across th2's seam, not a turn back round."""
    seg, grid = rrr_slice.segmentation, rrr_slice.grid
    plan = plan_across_the_seam(rrr_slice)
    plan["global_paths"] = plan["global_paths"] * 2
    line = drawn_global_path(plan_figure(rrr_slice, plan).axes[0], 1).get_xydata()
    # Its vertices but the ends of the pieces at the bounds of the turn drawn.
    bounds = np.degrees(grid.axes[0].low - grid.axes[0].step / 2) + np.array([0.0, 360.0])
    vertices = line[np.all(np.isfinite(line), axis=1)
                    & ~np.any(np.isclose(line[:, :1], bounds), axis=1)]
    assert len(vertices) >= 2
    (patch,) = plan["global_paths"][0]
    assert np.isin(grid.cells_of(np.radians(vertices)), seg.patches[patch].cells).all()
    steps = np.diff(line, axis=0)
    steps = steps[np.all(np.isfinite(steps), axis=1)]
    assert np.all(np.abs(steps) <= 180.0)
    joints = np.degrees(grid.unwrap([w["joints"] for w in plan["waypoints"]]))[:, 1:]
    assert np.linalg.norm(steps, axis=1).sum() < 2 * np.linalg.norm(joints[-1] - joints[0])


def check_space_plan_figure(figure, roadmap, plan, tmp_path):
    """The plan figure off a 2-D grid: the joints in 3-D, the pose track in
    3-D, every joint against the path, the global paths and ends in the
    figure's legend."""
    written(figure, tmp_path)
    mechanism = roadmap.mechanism
    legs, pose, joints = figure.axes[:3]
    units = ["deg" if n.startswith("th") else "length" for n in mechanism.joint_names]
    assert [legs.get_xlabel(), legs.get_ylabel(), legs.get_zlabel()] == [
        f"{n} [{u}]" for n, u in zip(mechanism.joint_names, units)]
    assert [pose.get_xlabel(), pose.get_ylabel(), pose.get_zlabel()] == [
        "x [length]", "y [length]", "alpha [deg]"]
    assert [line.get_label() for line in joints.get_lines()][:3] == [
        f"{n} [{u}]" for n, u in zip(mechanism.joint_names, units)]
    legend = legend_texts(figure.legends[0])
    assert sum(t.startswith("global path") for t in legend) == len(plan["global_paths"])
    assert any(t.startswith("start (alpha = ") for t in legend)
    assert any(t.startswith("goal (alpha = ") for t in legend)


def test_a_plan_on_a_refined_3d_roadmap_draws_joints_and_pose_track(adaptive_roadmap, tmp_path):
    plan = plan_in_one_patch(adaptive_roadmap)
    check_space_plan_figure(plan_figure(adaptive_roadmap, plan), adaptive_roadmap, plan,
                            tmp_path)


@pytest.mark.slow
def test_a_plan_on_the_full_roadmap_draws_both_paths_and_rho1_moving(full_roadmap, full_planner,
                                                                   tmp_path):
    # The pocket (test_full_roadmap): the same legs, both modes, rho1 must move.
    legs, alphas = (27.5, 31.67154934, 2.14117832), (-1.7627825445142729, 2.7584625675676517)
    plan = full_planner.plan((*legs, alphas[0]), (*legs, alphas[1])).to_dict()
    figure = plan_figure(full_roadmap, plan)
    check_space_plan_figure(figure, full_roadmap, plan, tmp_path)
    rho1 = figure.axes[2].get_lines()[0].get_ydata()
    assert np.ptp(rho1) > 1.0
    patches = {t.get_text() for t in figure.axes[2].texts}
    assert patches <= {str(p) for p in full_roadmap.segmentation.patches}


def test_a_plan_on_a_torus_of_turning_joints_is_drawn_in_degrees(rrr_torus, tmp_path):
    plan = plan_in_one_patch(rrr_torus)
    figure = plan_figure(rrr_torus, plan)
    check_space_plan_figure(figure, rrr_torus, plan, tmp_path)
    lines = [line.get_data_3d() for line in figure.axes[0].get_lines()]
    values = np.concatenate([np.ravel(v) for line in lines for v in line])
    values = values[np.isfinite(values)]
    assert np.all((values >= -180.0 - 7.5) & (values < 180.0))


def test_a_five_bar_torus_plan_keeps_the_2d_look(five_bar_torus, tmp_path):
    figure = plan_figure(five_bar_torus, plan_in_one_patch(five_bar_torus))
    written(figure, tmp_path)
    assert figure.axes[0].get_xlabel() == "th1 [deg]"
    assert figure.axes[1].get_zlabel() == "y [length]"
    figure = field_figure(five_bar_torus)
    written(figure, tmp_path)
    assert_integer_count_bar(figure, DEFAULT_FIVE_BAR.max_solutions)


def test_a_plan_off_a_2d_grid_in_a_scene_gains_the_base_plane(adaptive_roadmap, tmp_path):
    plan = plan_in_one_patch(adaptive_roadmap)
    assert len(plan_figure(adaptive_roadmap, plan).axes) == 3
    world = Planner(adaptive_roadmap).apply_scene(
        load_scene(CONFIG / "scenes" / "paper_narrowed.yaml"))
    figure = plan_figure(adaptive_roadmap, plan, world)
    check_space_plan_figure(figure, adaptive_roadmap, plan, tmp_path)
    assert len(figure.axes) == 4
    base = figure.axes[3]
    assert base.get_title() == ("base plane: the scene, the bodies at start and goal\n"
                                "(obstacle clearance 0.5)")
    assert [(tuple(c.center), c.radius) for c in base.patches
            if isinstance(c, Circle)] == [((6.0, 28.0), 2.0)]
    assert {"post", "plate"} <= {t.get_text() for t in base.texts}
    # At each end three legs and the platform, beside the obstacle "plate".
    assert [line.get_color() for line in base.get_lines()].count("tab:green") == 3
    assert sum(isinstance(p, Polygon) for p in base.patches) == 3


def test_a_scene_panel_needs_the_platform_in_the_base_plane(five_bar_torus, monkeypatch):
    plan = plan_in_one_patch(five_bar_torus)
    world = Planner(five_bar_torus).apply_scene(EMPTY_SCENE)
    # A pose whose second coordinate is an angle places no point in the plane.
    monkeypatch.setattr(type(five_bar_torus.mechanism), "angular", (False, True))
    with pytest.raises(InvalidInputError, match="5R's pose has no two lengths"):
        plan_figure(five_bar_torus, plan, world)


def test_the_slice_of_a_3d_roadmap_refuses_a_plane_off_two_axes(planes_roadmap):
    with pytest.raises(InvalidInputError, match="fixes all axes but two"):
        slice_figure(planes_roadmap, {})
    with pytest.raises(InvalidInputError, match="draw 2-D grids"):
        field_figure(planes_roadmap)
