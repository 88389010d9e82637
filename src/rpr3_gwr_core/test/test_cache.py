"""The on-disk roadmap cache: a second call loads what the first built, and
a damaged entry is rebuilt rather than trusted."""

import os

import numpy as np

from rpr3_gwr_core.io.cache import cached_roadmap
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice

GRID = rho1_slice(rho1=17, step=1.0)


def _same(a, b):
    np.testing.assert_array_equal(a.segmentation.patch, b.segmentation.patch)
    np.testing.assert_array_equal(a.segmentation.field.poses, b.segmentation.field.poses)
    assert set(a.segmentation.gates) == set(b.segmentation.gates)


def test_a_second_call_loads_the_same_roadmap(tmp_path):
    built, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))
    assert not hit
    loaded, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))
    assert hit
    _same(built, loaded)


def test_a_damaged_entry_is_rebuilt(tmp_path):
    built, _ = cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))
    (entry,) = [e for e in tmp_path.iterdir() if e.is_dir()]
    os.remove(entry / "margin.npy")
    rebuilt, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))
    assert not hit
    _same(built, rebuilt)
    assert cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))[1]
