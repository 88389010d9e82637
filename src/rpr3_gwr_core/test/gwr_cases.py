"""Cases and helpers shared by the core's tests (imported by name, so it is
not a conftest: the repository has two test folders)."""

import math

import numpy as np

from rpr3_gwr_core.paper import rho1_slice
from rpr3_gwr_core.mechanisms.rpr3 import PAPER_GEOMETRY, ThreeRPR

# The paper's four example configurations at rho1 = 17: (rho2, rho3, alpha [deg]).
PAPER_EXAMPLES = [(12.0, 18.0, 122.82), (10.0, 25.0, -24.24),
                  (20.0, 25.0, 29.47), (20.0, 25.0, 96.13)]

OTHER_GEOMETRY = ThreeRPR(a2=(12.0, 0.0), a3=(2.0, 9.0), d1=10.0, d3=12.0, beta=0.9)

# Coarse cases: name -> (geometry, grid).  The other geometry also has tests
# of its own at rho1 = 7.7 and 10 in test_segmentation.py.
COARSE_CASES = {
    "paper_rho17_step0.25": (PAPER_GEOMETRY, rho1_slice(rho1=17.0, step=0.25)),
    "paper_rho13_step0.25": (PAPER_GEOMETRY, rho1_slice(rho1=13.0, step=0.25)),
    "paper_rho30_step0.25": (PAPER_GEOMETRY, rho1_slice(rho1=30.0, step=0.25)),
    "other_rho10.1_step0.25": (OTHER_GEOMETRY, rho1_slice(rho1=10.1, rho2_range=(0.0, 30.0),
                                                    rho3_range=(0.0, 30.0), step=0.25)),
}


def nearest_slot(field, cell, alpha):
    """Slot of the solution of ``cell`` whose orientation is nearest ``alpha`` [rad]."""
    n = int(field.count[cell])
    gap = np.abs(np.angle(np.exp(1j * (field.poses[cell, :n, 2] - alpha))))
    return int(np.argmin(gap))


def deg(value):
    return math.radians(value)
