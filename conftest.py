"""Fixtures of both test folders: one roadmap cache per test session, so the
full 3-DOF roadmap is built once whether a core test, the CLI or a node asks
for it first, and nothing outside the session's temporary folder is read."""

import os
import pathlib
import sys

import pytest

# The independent pose-space reference (pose_reference) lives with the core's
# tests; the integration tests check the service's answers with it too.
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent / "src" / "rpr3_gwr_core"
                       / "test"))


@pytest.fixture(scope="session", autouse=True)
def roadmap_cache(tmp_path_factory):
    """The session's roadmap cache folder, also ``$RPR3_GWR_CACHE`` for the
    processes the tests start."""
    folder = str(tmp_path_factory.mktemp("roadmap-cache"))
    previous = os.environ.get("RPR3_GWR_CACHE")
    os.environ["RPR3_GWR_CACHE"] = folder
    try:
        yield folder
    finally:
        if previous is None:
            os.environ.pop("RPR3_GWR_CACHE", None)
        else:
            os.environ["RPR3_GWR_CACHE"] = previous


@pytest.fixture(scope="session")
def full_planning(roadmap_cache):
    """The full 3-DOF roadmap of the default box and its planning index,
    from the session's cache."""
    from rpr3_gwr_core import PAPER_GEOMETRY
    from rpr3_gwr_core.io.cache import cached_planning
    from rpr3_gwr_core.paper import FULL_BASE_GRID, FULL_REFINEMENT

    roadmap, index, _ = cached_planning(PAPER_GEOMETRY, FULL_BASE_GRID, roadmap_cache,
                                        refinement=FULL_REFINEMENT)
    return roadmap, index


@pytest.fixture(scope="session")
def full_roadmap(full_planning):
    """The full 3-DOF roadmap of the default box."""
    return full_planning[0]


@pytest.fixture(scope="session")
def full_planner(full_planning):
    """A planner on the full 3-DOF roadmap, its index built once a session."""
    from rpr3_gwr_core.planning import Planner

    return Planner(*full_planning)
