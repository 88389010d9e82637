"""The on-disk roadmap cache: a second call loads what the first built, a
damaged entry is rebuilt rather than trusted (see also
test_cache_integrity.py), a cache that cannot be written still gives the
roadmap, and the cache is bounded, least recently used entries first."""

import errno
import os
import shutil
import time
import warnings

import numpy as np
import pytest

from rpr3_gwr_core import InvalidInputError, build_roadmap
from rpr3_gwr_core.io import cache
from rpr3_gwr_core.io.cache import CacheWarning, STALE_STAGING_SECONDS, cache_key, cached_roadmap
from rpr3_gwr_core.paper import PAPER_GEOMETRY, rho1_slice
from rpr3_gwr_core.workspace import AdaptiveGrid

GRID = rho1_slice(rho1=17, step=1.0)
OTHERS = (rho1_slice(rho1=13, step=1.0), rho1_slice(rho1=15, step=1.0))


def _same(a, b):
    np.testing.assert_array_equal(a.segmentation.patch, b.segmentation.patch)
    np.testing.assert_array_equal(a.segmentation.field.poses, b.segmentation.field.poses)
    assert set(a.segmentation.gates) == set(b.segmentation.gates)


def _entries(folder):
    return {p.name for p in folder.iterdir() if p.is_dir() and not p.name.endswith(".tmp")}


def _key(grid):
    return cache_key(PAPER_GEOMETRY, grid)


def _bytes(entry):
    return sum(f.stat().st_size for f in entry.iterdir())


def _age(path, seconds):
    then = time.time() - seconds
    os.utime(path, (then, then))


@pytest.fixture(scope="module")
def fresh():
    return build_roadmap(PAPER_GEOMETRY, GRID)


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
    with pytest.warns(CacheWarning, match="margin.npy"):
        rebuilt, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))
    assert not hit
    _same(built, rebuilt)
    assert cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))[1]


@pytest.mark.parametrize("where", ["below a file", "a file"])
def test_a_cache_folder_that_cannot_be_made_still_gives_the_roadmap(tmp_path, fresh, where):
    blocker = tmp_path / "blocker"
    blocker.write_text("not a folder")
    folder = blocker / "cache" if where == "below a file" else blocker
    for _ in range(2):
        with pytest.warns(CacheWarning, match="not cached"):
            roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
        assert not hit
        _same(roadmap, fresh)
    assert blocker.read_text() == "not a folder"


def test_a_read_only_cache_folder_serves_its_entries_and_builds_the_others(
        tmp_path, fresh, monkeypatch):
    folder = str(tmp_path)
    cached_roadmap(PAPER_GEOMETRY, OTHERS[0], folder)
    # Mode 0o555 does not stop root, who runs these tests: the calls a
    # read-only folder refuses to any other user refuse here.
    for name in ("mkdir", "rename", "utime"):
        real = getattr(os, name)

        def refused(path, *args, real=real, **kwargs):
            if os.fspath(path).startswith(folder):
                raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), path)
            return real(path, *args, **kwargs)

        monkeypatch.setattr(os, name, refused)
    with pytest.warns(CacheWarning, match="not cached"):
        roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, folder)
    assert not hit
    _same(roadmap, fresh)
    assert _entries(tmp_path) == {_key(OTHERS[0])}
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        assert cached_roadmap(PAPER_GEOMETRY, OTHERS[0], folder)[1]


def test_the_cache_is_bounded_least_recently_used_first(tmp_path):
    folder = str(tmp_path)
    older, newer = OTHERS
    for grid in OTHERS:
        cached_roadmap(PAPER_GEOMETRY, grid, folder)
    _age(tmp_path / _key(older), 3600)
    _age(tmp_path / _key(newer), 1800)
    assert cached_roadmap(PAPER_GEOMETRY, older, folder)[1]  # a load is a use
    size = max(_bytes(tmp_path / _key(g)) for g in OTHERS)
    cached_roadmap(PAPER_GEOMETRY, GRID, folder, max_bytes=2 * size + size // 2)
    assert _entries(tmp_path) == {_key(older), _key(GRID)}


@pytest.mark.parametrize("given", ["argument", "environment"])
def test_the_entry_returned_is_kept_above_the_bound(tmp_path, fresh, monkeypatch, given):
    folder = str(tmp_path)
    cached_roadmap(PAPER_GEOMETRY, OTHERS[0], folder)
    bound = {}
    if given == "argument":
        bound["max_bytes"] = 0
    else:
        monkeypatch.setenv("RPR3_GWR_CACHE_MAX_BYTES", "0")
    roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, folder, **bound)
    assert not hit
    assert _entries(tmp_path) == {_key(GRID)}
    roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, folder, **bound)
    assert hit
    _same(roadmap, fresh)


@pytest.mark.parametrize("bound", [-1, 1.5, True, "4GB"])
def test_a_bad_bound_is_refused(tmp_path, bound):
    with pytest.raises(InvalidInputError, match="max_bytes"):
        cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path), max_bytes=bound)


def test_a_bad_bound_in_the_environment_is_refused(tmp_path, monkeypatch):
    monkeypatch.setenv("RPR3_GWR_CACHE_MAX_BYTES", "4GB")
    with pytest.raises(InvalidInputError, match="RPR3_GWR_CACHE_MAX_BYTES"):
        cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path))


def test_eviction_removes_abandoned_staging_folders_and_nothing_foreign(tmp_path):
    key = _key(GRID)
    young, old = tmp_path / f"{key}.young.tmp", tmp_path / f"{key}.old.tmp"
    for staging in (young, old):
        staging.mkdir()
        (staging / "poses.npy").write_bytes(b"\0" * 64)
    _age(old, STALE_STAGING_SECONDS + 60)
    foreign = tmp_path / "notes"
    foreign.mkdir()
    _age(foreign, 10**6)
    lookalike = tmp_path / ("0" * 24)
    lookalike.write_text("a file named like an entry")
    cached_roadmap(PAPER_GEOMETRY, GRID, str(tmp_path), max_bytes=0)
    assert young.is_dir() and not old.exists()
    assert foreign.is_dir() and lookalike.is_file()
    assert _entries(tmp_path) == {key, "notes"}


def test_eviction_skips_entries_another_process_removes_meanwhile(tmp_path, monkeypatch):
    folder = str(tmp_path)
    for grid in OTHERS:
        cached_roadmap(PAPER_GEOMETRY, grid, folder)
    gone = str(tmp_path / _key(OTHERS[0]))
    measure = cache._folder_bytes

    def racing(path):
        if path == gone:
            shutil.rmtree(path)
        return measure(path)

    monkeypatch.setattr(cache, "_folder_bytes", racing)
    cached_roadmap(PAPER_GEOMETRY, GRID, folder, max_bytes=0)
    assert _entries(tmp_path) == {_key(GRID)}


def test_an_entry_evicted_while_it_loads_is_a_plain_miss(tmp_path, fresh, monkeypatch):
    folder = str(tmp_path)
    cached_roadmap(PAPER_GEOMETRY, GRID, folder)
    read = cache._read

    def racing(entry, name, spec, verify):
        if name == "poses":  # another process evicts the entry between two arrays
            os.rename(entry, entry + ".evicted.tmp")
        return read(entry, name, spec, verify)

    monkeypatch.setattr(cache, "_read", racing)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CacheWarning)
        roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, folder)
    assert not hit
    _same(roadmap, fresh)


def test_an_entry_is_found_by_the_roadmap_s_own_grid(tmp_path):
    built, index, _ = cache.cached_planning(PAPER_GEOMETRY, GRID, str(tmp_path))
    found = cache.find_cached_planning(PAPER_GEOMETRY, built.grid, str(tmp_path))
    assert found is not None
    _same(found[0], built)
    assert found[1].clearances == index.clearances
    assert cache.find_cached_planning(PAPER_GEOMETRY, OTHERS[0], str(tmp_path)) is None
    assert cache.find_cached_planning(PAPER_GEOMETRY, GRID, str(tmp_path / "none")) is None


def test_an_adaptive_entry_is_found_by_its_refined_grid_only(tmp_path):
    base = rho1_slice(rho1=17, step=2.0)
    built, _, _ = cache.cached_planning(PAPER_GEOMETRY, base, str(tmp_path), refinement=2)
    found = cache.find_cached_planning(PAPER_GEOMETRY, built.grid, str(tmp_path))
    assert found is not None and found[0].grid == built.grid
    # The same base and refinement, other refined blocks: not this entry's roadmap.
    other = AdaptiveGrid(base, 2, built.grid.blocks[1:])
    assert cache.find_cached_planning(PAPER_GEOMETRY, other, str(tmp_path)) is None
