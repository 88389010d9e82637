"""The roadmap cache never serves a damaged entry: each way of damaging one on
disk is caught at the next load, which warns, rebuilds and returns what a
fresh build gives.

Each damage to an array is tried twice: with the header's checksums left as
they were (what a disk, a crash or a hand edit leaves) and with them
rewritten to match the damaged files (what a faulty writer would leave), so
that the checksums and the value checks behind them are both tested."""

import json
import os
import shutil
import zlib

import numpy as np
import pytest

from rpr3_gwr_core import PAPER_GEOMETRY, build_roadmap
from rpr3_gwr_core.io import cache as cache_module
from rpr3_gwr_core.io.cache import CacheWarning, cached_roadmap
from rpr3_gwr_core.io.export import roadmap_arrays
from rpr3_gwr_core.paper import rho1_slice

GRID = rho1_slice(rho1=17, step=1.0)


@pytest.fixture(scope="module")
def fresh():
    return build_roadmap(PAPER_GEOMETRY, GRID)


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A cache folder holding one good entry, copied by each test."""
    folder = tmp_path_factory.mktemp("pristine")
    cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    return folder


@pytest.fixture
def cache(pristine, tmp_path):
    folder = tmp_path / "cache"
    shutil.copytree(pristine, folder)
    (entry,) = folder.iterdir()
    return folder, entry


def assert_same(roadmap, fresh):
    got, want = roadmap_arrays(roadmap), roadmap_arrays(fresh)
    for name in ("count", "poses", "margin", "region", "patch"):
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)
    assert len(got["links"]) == len(want["links"])
    for a, b in zip(got["links"], want["links"]):
        np.testing.assert_array_equal(a, b)
    assert set(roadmap.segmentation.gates) == set(fresh.segmentation.gates)


def _edit(entry, name, change):
    array = np.load(entry / f"{name}.npy")
    np.save(entry / f"{name}.npy", change(array.copy()))


def _restamp(entry):
    """Rewrite the header's checksums, dtypes and shapes to match the files."""
    header = json.loads((entry / "header.json").read_text())
    for name in header["arrays"]:
        array = np.ascontiguousarray(np.load(entry / f"{name}.npy"))
        header["arrays"][name] = {"dtype": array.dtype.str, "shape": list(array.shape),
                                  "crc32": zlib.crc32(array.tobytes())}
    _write_header(entry, header)


def _write_header(entry, header):
    body = {k: v for k, v in header.items() if k != "checksum"}
    header["checksum"] = zlib.crc32(json.dumps(body, sort_keys=True,
                                               separators=(",", ":")).encode())
    (entry / "header.json").write_text(json.dumps(header))


def _scramble_patches(patch):
    return patch[np.random.default_rng(3).permutation(len(patch))]


def _negate(margin):
    return -margin


def _nan(margin):
    margin[:] = np.nan
    return margin


def _zero(poses):
    return np.zeros_like(poses)


def _six(count):
    return np.full_like(count, 6)


def _seven(count):
    return np.full_like(count, 7)


def _float(links):
    return links.astype(np.float64)


def _out_of_slots(links):
    return np.full_like(links, 9)


def _negative(region):
    region[np.argmax(region)] = -1
    return region


def _shift(patch):
    return np.where(patch > 0, patch + 1000, 0).astype(patch.dtype)


def _past_the_nodes(indices):
    indices[indices.size // 2] = np.iinfo(indices.dtype).max
    return indices


def _doubled(indptr):
    return indptr * 2


def _cut_short(distances):
    return distances[:, :-1]


def _shuffled(array):
    return array[np.random.default_rng(5).permutation(len(array))]


def _nine(slots):
    return np.full_like(slots, 9)


def _plus_one(values):
    return values + 1


def _flipped(flags):
    return ~flags


def _swapped(pairs):
    return pairs[:, ::-1].copy()


def _reversed(rows):
    return rows[::-1].copy()


def _first_patch_reversed(entry):
    """The first patch's cells and slots in descending order: still each
    solution of the patch once."""
    size = int(np.load(entry / "table_patch_starts.npy")[1])
    for name in ("table_patch_cells", "table_patch_slots"):
        _edit(entry, name, lambda array: np.concatenate([array[:size][::-1], array[size:]]))


ARRAY_DAMAGE = {
    "index edges past the nodes": ("index_indices", _past_the_nodes),
    "index offsets past its edges": ("index_indptr", _doubled),
    "index gate distances cut short": ("index_distances", _cut_short),
    "margin signs flipped": ("margin", _negate),
    "margins NaN": ("margin", _nan),
    "poses zeroed": ("poses", _zero),
    "counts set to 6": ("count", _six),
    "counts above the mechanism's": ("count", _seven),
    "float links": ("links_0", _float),
    "links naming no slot": ("links_1", _out_of_slots),
    "patch ids scrambled": ("patch", _scramble_patches),
    "patch ids past the regions": ("patch", _shift),
    "negative region ids": ("region", _negative),
    "table patch cells shuffled": ("table_patch_cells", _shuffled),
    "table patch slots naming no slot": ("table_patch_slots", _out_of_slots),
    "table patch offsets past its cells": ("table_patch_starts", _doubled),
    "table patch regions off by one": ("table_patch_region", _plus_one),
    "table patch layers off by one": ("table_patch_layer", _plus_one),
    "table patch aspects flipped": ("table_patch_aspect", _negate),
    "table patch solutions off by one": ("table_patch_solutions", _plus_one),
    "table gate cells flipped": ("table_patch_gate", _flipped),
    "table gate patches swapped": ("table_gate_patches", _swapped),
    "table gate faces reversed": ("table_gate_faces", _reversed),
    "table gate offsets past its faces": ("table_gate_starts", _doubled),
    "table gate widths negative": ("table_gate_width", _negate),
    "patch areas NaN": ("patch_area", _nan),
    "patch areas negative": ("patch_area", _negate),
}

# Caught by their checksums alone: which cells of a patch lie on its singular
# boundary is derived from every face's links, as long as deriving the
# segmentation again, which the stored tables spare a load; nothing but the
# exported documents reads them.
STALE_DAMAGE = {
    "table singular cells flipped": ("table_patch_singular", _flipped),
}


def _check_rebuilt(folder, entry, fresh):
    with pytest.warns(CacheWarning, match=entry.name):
        roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    assert not hit
    assert_same(roadmap, fresh)
    # The rebuilt entry is good: the next call loads it.
    roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    assert hit
    assert_same(roadmap, fresh)


@pytest.mark.parametrize("restamped", [False, True], ids=["stale checksums", "restamped"])
@pytest.mark.parametrize("damage", sorted(ARRAY_DAMAGE))
def test_a_damaged_array_is_caught_and_rebuilt(cache, fresh, damage, restamped):
    folder, entry = cache
    name, change = ARRAY_DAMAGE[damage]
    _edit(entry, name, change)
    if restamped:
        _restamp(entry)
    _check_rebuilt(folder, entry, fresh)


@pytest.mark.parametrize("restamped", [False, True], ids=["stale checksums", "restamped"])
def test_a_patch_whose_cells_do_not_ascend_is_caught_and_rebuilt(cache, fresh, restamped):
    folder, entry = cache
    _first_patch_reversed(entry)
    if restamped:
        _restamp(entry)
    _check_rebuilt(folder, entry, fresh)


@pytest.mark.parametrize("damage", sorted(STALE_DAMAGE))
def test_damage_under_stale_checksums_is_caught_and_rebuilt(cache, fresh, damage):
    folder, entry = cache
    name, change = STALE_DAMAGE[damage]
    _edit(entry, name, change)
    _check_rebuilt(folder, entry, fresh)


def _header(entry):
    return json.loads((entry / "header.json").read_text())


def _empty_list(entry):
    (entry / "header.json").write_text("[]")


def _arrays_five(entry):
    header = _header(entry)
    header["arrays"] = 5
    (entry / "header.json").write_text(json.dumps(header))


def _arrays_five_restamped(entry):
    header = _header(entry)
    header["arrays"] = 5
    _write_header(entry, header)


def _not_json(entry):
    text = (entry / "header.json").read_text()
    (entry / "header.json").write_text(text[:len(text) // 2])


def _other_grid(entry):
    header = _header(entry)
    header["grid"] = rho1_slice(rho1=17, step=2.0).to_dict()
    _write_header(entry, header)


def _no_margin(entry):
    os.remove(entry / "margin.npy")


def _truncated_poses(entry):
    data = (entry / "poses.npy").read_bytes()
    (entry / "poses.npy").write_bytes(data[:len(data) - 8])


def _no_gate_table(entry):
    os.remove(entry / "table_gate_faces.npy")


def _pickled_patch(entry):
    patch = np.load(entry / "patch.npy")
    np.save(entry / "patch.npy", patch.astype(object), allow_pickle=True)


FILE_DAMAGE = {
    "header []": _empty_list,
    "header arrays 5": _arrays_five,
    "header arrays 5, restamped": _arrays_five_restamped,
    "header cut short": _not_json,
    "header of another grid, restamped": _other_grid,
    "margin.npy missing": _no_margin,
    "table_gate_faces.npy missing": _no_gate_table,
    "poses.npy cut short": _truncated_poses,
    "patch.npy pickled": _pickled_patch,
}


@pytest.mark.parametrize("damage", sorted(FILE_DAMAGE))
def test_a_damaged_header_or_file_is_caught_and_rebuilt(cache, fresh, damage):
    folder, entry = cache
    FILE_DAMAGE[damage](entry)
    _check_rebuilt(folder, entry, fresh)


def _checks_made(monkeypatch):
    """Counts of the array checksums and value checks the loads make."""
    made = {"checksums": 0, "values": 0}
    checksum, values = cache_module._checksum, cache_module._check_values

    def counted_checksum(data):
        made["checksums"] += isinstance(data, np.ndarray)
        return checksum(data)

    def counted_values(*args):
        made["values"] += 1
        return values(*args)

    monkeypatch.setattr(cache_module, "_checksum", counted_checksum)
    monkeypatch.setattr(cache_module, "_check_values", counted_values)
    return made


def test_an_entry_checked_once_is_mapped_unread_while_its_files_are_unchanged(
        cache, fresh, monkeypatch):
    folder, entry = cache
    made = _checks_made(monkeypatch)
    roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    assert hit and made == {"checksums": len(_header(entry)["arrays"]), "values": 1}
    assert (entry / "checked.json").is_file()
    for _ in range(2):
        roadmap, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
        assert hit
        assert_same(roadmap, fresh)
    assert made["values"] == 1 and made["checksums"] == len(_header(entry)["arrays"])


@pytest.mark.parametrize("damage", ["margin signs flipped", "table patch cells shuffled"])
def test_a_file_rewritten_after_the_check_is_checked_again(cache, fresh, damage):
    folder, entry = cache
    cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    assert (entry / "checked.json").is_file()
    name, change = ARRAY_DAMAGE[damage]
    _edit(entry, name, change)
    _restamp(entry)
    _check_rebuilt(folder, entry, fresh)


def test_a_copied_entry_is_checked_again(cache, tmp_path, monkeypatch):
    folder, entry = cache
    cached_roadmap(PAPER_GEOMETRY, GRID, str(folder))
    copy = tmp_path / "copy"
    # copytree keeps the files' sizes and times; the inodes are new.
    shutil.copytree(folder, copy)
    made = _checks_made(monkeypatch)
    _, hit = cached_roadmap(PAPER_GEOMETRY, GRID, str(copy))
    assert hit and made["values"] == 1
