"""Shared, session-scoped fixtures: the paper's roadmap is built once, the
other geometries and rho1 values on coarse grids, each segmented at most once
per method."""

import pytest

from gwr_cases import COARSE_CASES
from rpr3_gwr_core.paper import PAPER_GRID, rho1_slice
from rpr3_gwr_core.workspace import compute_field
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY
from rpr3_gwr_core.workspace.roadmap import build_roadmap, roadmap_graph
from rpr3_gwr_core.workspace.segmentation import segment


class CaseCache:
    """Fields and segmentations of the coarse cases, computed on first use."""

    def __init__(self):
        self._fields, self._segs, self._graphs = {}, {}, {}

    def field(self, name):
        if name not in self._fields:
            geometry, grid = COARSE_CASES[name]
            self._fields[name] = compute_field(geometry, grid)
        return self._fields[name]

    def segmentation(self, name, method="components"):
        key = (name, method)
        if key not in self._segs:
            self._segs[key] = segment(self.field(name), method=method)
        return self._segs[key]

    def graph(self, name):
        if name not in self._graphs:
            self._graphs[name] = roadmap_graph(self.segmentation(name))
        return self._graphs[name]


@pytest.fixture(scope="session")
def paper_roadmap():
    """The paper's roadmap: default geometry, 401 x 401 grid, rho1 = 17."""
    return build_roadmap(PAPER_GEOMETRY, PAPER_GRID)


@pytest.fixture(scope="session")
def cases():
    return CaseCache()


@pytest.fixture(scope="session")
def coarse_paper_roadmap():
    """A cheap roadmap (step 0.5) for export and figure tests."""
    return build_roadmap(PAPER_GEOMETRY, rho1_slice(step=0.5))
