"""Shared, session-scoped fixtures: the paper's roadmap is built once, the
other geometries and rho1 values on coarse grids, each segmented at most once
per method."""

import math

import numpy as np
import pytest

from rpr3_gwr_core.field import Grid, compute_field
from rpr3_gwr_core.geometry import PAPER_GEOMETRY, Geometry
from rpr3_gwr_core.roadmap import build_roadmap, roadmap_graph
from rpr3_gwr_core.segmentation import segment

# The paper's four example configurations at rho1 = 17: (rho2, rho3, alpha [deg]).
PAPER_EXAMPLES = [(12.0, 18.0, 122.82), (10.0, 25.0, -24.24),
                  (20.0, 25.0, 29.47), (20.0, 25.0, 96.13)]

OTHER_GEOMETRY = Geometry(a2=(12.0, 0.0), a3=(2.0, 9.0), d1=10.0, d3=12.0, beta=0.9)

# Coarse cases: name -> (geometry, grid).  rho1 = 10.1 for the other geometry
# because integer rho1 puts a singular crossing exactly on a grid line (see
# test_segmentation.py, the xfail tests of that geometry).
COARSE_CASES = {
    "paper_rho17_step0.25": (PAPER_GEOMETRY, Grid(rho1=17.0, step=0.25)),
    "paper_rho13_step0.25": (PAPER_GEOMETRY, Grid(rho1=13.0, step=0.25)),
    "paper_rho30_step0.25": (PAPER_GEOMETRY, Grid(rho1=30.0, step=0.25)),
    "other_rho10.1_step0.25": (OTHER_GEOMETRY, Grid(rho1=10.1, rho2_range=(0.0, 30.0),
                                                    rho3_range=(0.0, 30.0), step=0.25)),
}


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
    return build_roadmap()


@pytest.fixture(scope="session")
def cases():
    return CaseCache()


@pytest.fixture(scope="session")
def coarse_paper_roadmap():
    """A cheap roadmap (step 0.5) for export and figure tests."""
    return build_roadmap(PAPER_GEOMETRY, Grid(step=0.5))


def nearest_slot(field, cell, alpha):
    """Slot of the solution of ``cell`` whose orientation is nearest ``alpha`` [rad]."""
    n = int(field.count[cell])
    gap = np.abs(np.angle(np.exp(1j * (field.poses[cell, :n, 2] - alpha))))
    return int(np.argmin(gap))


def deg(value):
    return math.radians(value)
