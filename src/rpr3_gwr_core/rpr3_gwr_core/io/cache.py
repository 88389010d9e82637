"""An on-disk cache of built roadmaps, keyed by mechanism, grid and format.

The only module of the core that touches the file system: the CLI and the
nodes use it so that a second call with the same mechanism and grid loads the
roadmap instead of rebuilding it.

Entries
-------
An entry is a folder named by :func:`cache_key` holding one ``.npy`` file per
array of :func:`~rpr3_gwr_core.io.export.roadmap_arrays` (``links`` as
``links_0``, ``links_1``, ...), one per array of the roadmap's planning index
(:func:`~rpr3_gwr_core.planning.search_index`, as ``index_<name>``), one
per table of its segmentation
(:meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.tables`, as
``table_<name>``) with ``patch_area``, each patch's area, so that a load
derives neither patches, gates nor the cells' volumes, and
``header.json``: the mechanism and grid documents, each array's dtype, shape
and CRC-32, and a CRC-32 of the header itself.  It is written to a staging
folder (``<key>.<random>.tmp``) and renamed into place, so a reader finds an
entry whole or not at all.

The arrays are mapped, copy on write, rather than read: processes that load
one entry share its pages (the full 3-DOF roadmap's entry, about 0.9 GB),
and nothing a process writes into them reaches the files or another
process.  :func:`save_planning_files` and :func:`map_planning_files` write
and map the same files outside the cache, for a roadmap that came from
elsewhere (the planner node's, received as messages).

Integrity
---------
A load checks that the header is well formed, passes its checksum and
describes the requested mechanism and grid; that each array has the listed
dtype and shape and passes its checksum; then the values the compiled passes
rely on and :func:`~rpr3_gwr_core.io.export.roadmap_from_arrays` does not
check: counts within ``0..max_solutions``, poses and margins finite exactly
where a solution exists, a sample of margins equal to the mechanism's margin
of their poses (a flipped sign would flip an aspect), region ids non-negative
and 0 on cells without solutions, patch ids 0 where there is no solution,
and the tables against the patch ids
(:meth:`~rpr3_gwr_core.workspace.segmentation.Segmentation.from_tables`).
An entry that fails is removed and rebuilt, with a :class:`CacheWarning`
naming the entry and what failed.

An entry that passes is stamped (``checked.json``: the header's checksum
and the size, modification time and inode of each of its files), and a
later load whose files all still match the stamp checks the header and the
planning index's shapes and ranges only, mapping the arrays without reading
them: the pages a plan never touches are never read.  A file rewritten,
replaced or copied no longer matches, and its entry is checked in full
again; damage that leaves a file's size, times and inode as they were (a
failing disk under the file system) is caught only by a load that checks in
full.  A cache that cannot be written keeps no stamp: each load checks in
full.  The checksums are CRC-32 (:mod:`zlib`)
rather than a cryptographic hash: they are there to catch damage, not
tampering (whoever can write an entry can rewrite its header too), and
over the full 3-DOF roadmap's arrays CRC-32 takes about 0.1 s, SHA-256 0.4 s.

Size bound
----------
Whenever an entry is stored, the least recently used entries (loading an
entry touches its folder) are removed until the entries total at most
``max_bytes`` (:func:`default_max_bytes`: ``$RPR3_GWR_CACHE_MAX_BYTES``, else
:data:`DEFAULT_MAX_BYTES`, 4 GiB: the full 3-DOF roadmap's entry of about
0.9 GB and about fifty 66 MB entries of 0.125 slices).  The entry just
stored is kept even if it alone exceeds the bound.  Only folders named as
entries count and are removed; staging folders are left to the processes
writing them unless they are older than :data:`STALE_STAGING_SECONDS` (left
by a process that died).  Entries that other processes remove meanwhile are
skipped.

Unwritable cache
----------------
When the cache folder cannot be created or written (read-only, full, a file
in the way), the roadmap is built and returned without being stored, with a
:class:`CacheWarning`.
"""

import hashlib
import io
import json
import math
import numbers
import os
import re
import shutil
import tempfile
import time
import warnings
import zlib

import numpy as np

from ..exceptions import InvalidInputError
from ..planning.index import INDEX_TYPES, CellSearchIndex
from ..planning.planner import build_cell_search_index
from ..workspace import build_roadmap, refine, refine_thin_regions
from ..workspace.progress import part
from ..workspace.segmentation import TABLE_TYPES
from .export import FIELD_TYPES, FORMAT, VERSION, roadmap_arrays, roadmap_from_arrays
from .paths import default_cache_dir

__all__ = ["CacheWarning", "DEFAULT_MAX_BYTES", "STALE_STAGING_SECONDS", "default_cache_dir",
           "default_max_bytes", "cache_key", "cached_roadmap", "cached_planning",
           "find_cached_planning", "save_planning_files", "map_planning_files"]

# Bump when a change of the algorithms changes roadmaps, so old entries are not reused.
ALGORITHM_REVISION = 6
# Bump when the files of an entry, or what its planning index holds, change, so
# old entries are misses (evicted in their turn) rather than damaged entries.
ENTRY_LAYOUT = 8

DEFAULT_MAX_BYTES = 4 * 2**30
"""Default bound of the cache's entries [bytes]."""

STALE_STAGING_SECONDS = 600.0
"""Age past which a staging folder is taken as abandoned [s]; writing the
largest entry takes seconds."""

_LINK_TYPE = "<i1"
_INDEX_PREFIX = "index_"
_TABLE_PREFIX = "table_"
_AREA = "patch_area"
_AREA_TYPE = "<f8"
_MARGIN_SAMPLES = 4096
_POSE_CHUNK = 32768
_STAMP = "checked.json"
_ENTRY_NAME = re.compile(r"[0-9a-f]{24}")
_STAGING_NAME = re.compile(r"[0-9a-f]{24}\..+\.tmp")


class CacheWarning(UserWarning):
    """A cache entry was damaged and rebuilt, or the cache cannot be written."""


def default_max_bytes():
    """``$RPR3_GWR_CACHE_MAX_BYTES``, else :data:`DEFAULT_MAX_BYTES` [bytes].

    Raises
    ------
    InvalidInputError
        If the variable is set but not a non-negative integer.
    """
    text = os.environ.get("RPR3_GWR_CACHE_MAX_BYTES")
    if not text:
        return DEFAULT_MAX_BYTES
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise InvalidInputError(f"RPR3_GWR_CACHE_MAX_BYTES must be a non-negative integer "
                                f"number of bytes, got {text!r}")
    return value


def cache_key(mechanism, grid, method="components", min_region_cells=8, refinement=None,
              thin_refinement=None):
    """Hex digest identifying a roadmap build."""
    build = {"format": FORMAT, "version": VERSION, "revision": ALGORITHM_REVISION,
             "layout": ENTRY_LAYOUT, "mechanism": mechanism.to_dict(), "grid": grid.to_dict(),
             "method": method, "min_region_cells": min_region_cells, "refinement": refinement}
    # Named only when asked for, so that the keys of other builds stay.
    if thin_refinement is not None:
        build["thin_refinement"] = thin_refinement
    text = json.dumps(build, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_roadmap(mechanism, grid, cache_dir=None, progress=None, refinement=None,
                   max_bytes=None, *, workers=map, thin_refinement=None):
    """Load a roadmap from the cache, or build and store it.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid
    cache_dir : str, optional
        Defaults to :func:`default_cache_dir`.
    progress : callable, optional
        Called as ``progress(stage, fraction)`` (the stage's name, the
        fraction of the work done) while the roadmap is built: through the
        refinement of ``grid``, :func:`~rpr3_gwr_core.workspace.build_roadmap`
        and the planning index; not on a load from the cache.
    refinement : int, optional
        Build on ``refine(mechanism, grid, refinement)`` (an adaptive grid)
        instead of ``grid`` itself.
    max_bytes : int, optional
        Bound of the cache's entries after storing one [bytes] (module doc);
        defaults to :func:`default_max_bytes`.
    workers : callable, optional
        A map-like callable, ``workers(function, iterable)`` yielding the
        results in order, such as ``ThreadPoolExecutor.map``: an entry's
        arrays are read and checksummed with it, a build works with it
        (:func:`~rpr3_gwr_core.workspace.build_roadmap`), in parallel with a
        thread pool's (CRC-32 and numpy release the interpreter's lock).
        The default, the builtin ``map``, works in the calling thread.
    thin_refinement : int, optional
        Build with :func:`~rpr3_gwr_core.workspace.refine_thin_regions` at
        this refinement (on the refined grid when ``refinement`` is given,
        at its refinement): the roadmap's grid is then ``grid`` itself or
        ``grid`` with the blocks around its thin regions refined.

    Returns
    -------
    roadmap : Roadmap
    hit : bool
        Whether it came from the cache.

    Raises
    ------
    InvalidInputError
        If ``max_bytes``, or ``$RPR3_GWR_CACHE_MAX_BYTES`` when it is not
        given, is not a non-negative integer.

    Warns
    -----
    CacheWarning
        When an entry is damaged (it is rebuilt) or the roadmap cannot be
        stored (it is returned all the same).
    """
    roadmap, _, hit = cached_planning(mechanism, grid, cache_dir, progress, refinement,
                                      max_bytes, workers=workers,
                                      thin_refinement=thin_refinement)
    return roadmap, hit


def cached_planning(mechanism, grid, cache_dir=None, progress=None, refinement=None,
                    max_bytes=None, *, workers=map, thin_refinement=None):
    """:func:`cached_roadmap` with the roadmap's planning index
    (:func:`~rpr3_gwr_core.planning.search_index`), built with it and
    stored in its entry: a :class:`~rpr3_gwr_core.planning.Planner` given
    both plans at once.

    Returns
    -------
    roadmap : Roadmap
    index : CellSearchIndex
    hit : bool
        Whether they came from the cache.
    """
    if max_bytes is None:
        max_bytes = default_max_bytes()
    elif isinstance(max_bytes, bool) or not isinstance(max_bytes, numbers.Integral) \
            or max_bytes < 0:
        raise InvalidInputError(f"max_bytes must be a non-negative integer, got {max_bytes!r}")
    directory = cache_dir or default_cache_dir()
    key = cache_key(mechanism, grid, refinement=refinement, thin_refinement=thin_refinement)
    path = os.path.join(directory, key)
    if os.path.isdir(path):
        try:
            roadmap, index = _load(path, (mechanism, grid, refinement, thin_refinement), workers)
        except (InvalidInputError, OSError, ValueError) as exc:
            # Unless another process evicted it meanwhile: that is a plain miss.
            if os.path.isdir(path):
                warnings.warn(f"roadmap cache entry {path} is damaged ({exc}); it is removed "
                              "and the roadmap rebuilt", CacheWarning, stacklevel=2)
                _discard(path)
        else:
            try:
                os.utime(path)
            except OSError:  # a read-only cache still serves, its recency unrecorded
                pass
            return roadmap, index, True
    begin = time.perf_counter()
    # Fractions of the work as the full 3-DOF roadmap's first build splits
    # it: the planning index takes about a third.
    built = 0.05 if refinement is not None else 0.0
    if refinement is not None:
        grid = refine(mechanism, grid, refinement, progress=part(progress, 0.0, built),
                      workers=workers)
    refined = time.perf_counter() - begin
    if thin_refinement is None:
        roadmap = build_roadmap(mechanism, grid, progress=part(progress, built, 0.7),
                                workers=workers)
    else:
        roadmap, _ = refine_thin_regions(mechanism, grid, thin_refinement,
                                         progress=part(progress, built, 0.7), workers=workers)
    if refinement is not None:
        roadmap.timings["refine"] = refined
    report = part(progress)
    report("planning index", 0.7)
    begin = time.perf_counter()
    index = build_cell_search_index(roadmap)
    roadmap.timings["index"] = time.perf_counter() - begin
    report("storing in the cache", 0.99)
    try:
        _store(directory, key, roadmap, index)
    except OSError as exc:
        warnings.warn(f"the roadmap is not cached: cannot write the cache folder {directory} "
                      f"({exc})", CacheWarning, stacklevel=2)
    else:
        _evict(directory, path, max_bytes)
    report("done", 1.0)
    return roadmap, index, False


def find_cached_planning(mechanism, grid, cache_dir=None, *, workers=map):
    """The roadmap and planning index of the entry built for a mechanism on
    a grid, if the cache holds it: for a roadmap received from elsewhere
    (the planner node's, published by a builder that loaded or built it
    through the same cache), whose index is then mapped rather than built.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid or AdaptiveGrid
        The roadmap's own grid: an adaptive grid's entry is the one built by
        refining its base grid as often.
    cache_dir : str, optional
        Defaults to :func:`default_cache_dir`.
    workers : callable, optional
        As :func:`cached_roadmap`'s.

    Returns
    -------
    (Roadmap, CellSearchIndex) or None
        None when there is no such entry, when it is damaged (it is left to
        the next :func:`cached_planning` of it to rebuild), or when it was
        built on another grid (an adaptive grid refined elsewhere).
    """
    refinement = getattr(grid, "refinement", None)
    base = grid if refinement is None else grid.base
    path = os.path.join(cache_dir or default_cache_dir(),
                        cache_key(mechanism, base, refinement=refinement))
    if not os.path.isdir(path):
        return None
    try:
        roadmap, index = _load(path, (mechanism, base, refinement, None), workers)
    except (InvalidInputError, OSError, ValueError):
        return None
    return (roadmap, index) if roadmap.grid == grid else None


def save_planning_files(folder, roadmap, index):
    """Write a roadmap and its planning index into an existing empty folder,
    as a cache entry's files (module doc).

    Raises
    ------
    OSError
        If they cannot be written.
    """
    _save(folder, roadmap, index)


def map_planning_files(folder, *, workers=map):
    """The roadmap and planning index of :func:`save_planning_files` (or of
    a cache entry), mapped copy on write and checked as a cache entry is.

    Parameters
    ----------
    folder : str
    workers : callable, optional
        A map-like callable the arrays are read and checksummed with, as
        :func:`cached_roadmap`'s.

    Returns
    -------
    roadmap : Roadmap
    index : CellSearchIndex

    Raises
    ------
    InvalidInputError
        If the files are damaged (naming what failed).
    OSError
        If they cannot be read.
    """
    return _load(folder, workers=workers)


def _checksum(data):
    """CRC-32 of an array's bytes, or of a JSON document's canonical text."""
    if isinstance(data, np.ndarray):
        return zlib.crc32(data.reshape(-1).view(np.uint8))
    return zlib.crc32(json.dumps(data, sort_keys=True, separators=(",", ":")).encode())


def _store(directory, key, roadmap, index):
    """Write an entry through a staging folder; raises OSError if it cannot."""
    os.makedirs(directory, exist_ok=True)
    staging = tempfile.mkdtemp(dir=directory, prefix=key + ".", suffix=".tmp")
    try:
        _save(staging, roadmap, index)
        os.rename(staging, os.path.join(directory, key))
    except OSError:
        shutil.rmtree(staging, ignore_errors=True)
        # The rename fails, harmlessly, when another process stored the entry meanwhile.
        if not os.path.isdir(os.path.join(directory, key)):
            raise


def _save(folder, roadmap, index):
    arrays = roadmap_arrays(roadmap)
    named = {name: np.ascontiguousarray(arrays[name], dtype=dtype)
             for name, dtype in FIELD_TYPES.items()}
    named.update({f"links_{k}": np.ascontiguousarray(match, dtype=_LINK_TYPE)
                  for k, match in enumerate(arrays["links"])})
    named.update({_INDEX_PREFIX + name: np.ascontiguousarray(array, dtype=INDEX_TYPES[name])
                  for name, array in index.arrays().items()})
    tables = roadmap.segmentation.tables()
    named.update({_TABLE_PREFIX + name: np.ascontiguousarray(array, dtype=TABLE_TYPES[name])
                  for name, array in tables.items()})
    areas = [roadmap.graph.nodes[pid]["area"] for pid in tables["patch_ids"].tolist()]
    named[_AREA] = np.array(areas, dtype=_AREA_TYPE)
    listing = {}
    for name, array in named.items():
        np.save(os.path.join(folder, name + ".npy"), array)
        listing[name] = {"dtype": array.dtype.str, "shape": list(array.shape),
                         "crc32": _checksum(array)}
    header = {"mechanism": roadmap.mechanism.to_dict(), "grid": roadmap.grid.to_dict(),
              "arrays": listing}
    header["checksum"] = _checksum(header)
    with open(os.path.join(folder, "header.json"), "w", encoding="utf-8") as stream:
        json.dump(header, stream)


def _load(folder, expected=None, workers=map):
    """The roadmap and planning index of an entry (module doc), which must
    be of ``expected = (mechanism, grid, refinement, thin_refinement)`` when given; raises
    InvalidInputError naming what failed, or OSError."""
    with open(os.path.join(folder, "header.json"), encoding="utf-8") as stream:
        try:
            header = json.load(stream)
        except ValueError as exc:
            raise InvalidInputError(f"header.json is not JSON: {exc}") from exc
    _check_header(header, expected)
    listing = header["arrays"]
    # Taken before the files are read, so that a file changed meanwhile
    # does not match the stamp that records this check.
    stamp = {"header": header["checksum"], "files": _file_stamps(folder, listing)}
    checked = _read_stamp(folder) == stamp
    # Largest first, so that with parallel workers no large one is left to
    # the end alone.
    names = sorted(listing, key=lambda name: -math.prod(listing[name]["shape"]))
    arrays = dict(zip(names, workers(
        lambda name: _read(folder, name, listing[name], verify=not checked), names)))
    index, tables = ({name[len(prefix):]: arrays.pop(name) for name in list(arrays)
                      if name.startswith(prefix)} for prefix in (_INDEX_PREFIX, _TABLE_PREFIX))
    areas = arrays.pop(_AREA)
    arrays["links"] = [arrays.pop(f"links_{k}")
                       for k in range(len(arrays) - len(FIELD_TYPES))]
    # Nothing compiled reads the arrays before their values are checked,
    # here or by the load that stamped the entry: the tables spare the
    # derivations that would.
    roadmap = roadmap_from_arrays(header["mechanism"], header["grid"], arrays, tables, areas,
                                  check=not checked)
    if not checked:
        _check_values(roadmap.mechanism, roadmap.grid, arrays)
    index = CellSearchIndex.from_arrays(roadmap, index)
    if not checked:
        _write_stamp(folder, stamp)
    return roadmap, index


def _file_stamps(folder, listing):
    """Size, modification time [ns] and inode of the header and of each
    array's file, by file name."""
    stamps = {}
    for name in ["header.json", *(name + ".npy" for name in sorted(listing))]:
        info = os.stat(os.path.join(folder, name))
        stamps[name] = [info.st_size, info.st_mtime_ns, info.st_ino]
    return stamps


def _read_stamp(folder):
    """The entry's stamp (module doc), None if it has none or an unreadable one."""
    try:
        with open(os.path.join(folder, _STAMP), encoding="utf-8") as stream:
            return json.load(stream)
    except (OSError, ValueError):
        return None


def _write_stamp(folder, stamp):
    """Stamp an entry checked in full, through a file renamed into place;
    a cache that cannot be written goes without."""
    try:
        handle, staging = tempfile.mkstemp(dir=folder, prefix=_STAMP + ".", suffix=".tmp")
    except OSError:
        return
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as stream:
            json.dump(stamp, stream)
        os.replace(staging, os.path.join(folder, _STAMP))
    except OSError:
        try:
            os.unlink(staging)
        except OSError:
            pass


def _check_header(header, expected):
    if not isinstance(header, dict) or set(header) != {"mechanism", "grid", "arrays", "checksum"}:
        raise InvalidInputError("header.json is not an entry's header")
    if header["checksum"] != _checksum({k: v for k, v in header.items() if k != "checksum"}):
        raise InvalidInputError("header.json fails its checksum")
    if expected is not None:
        _check_names(header, *expected)
    listing = header["arrays"]
    others = dict({_INDEX_PREFIX + name: dtype for name, dtype in INDEX_TYPES.items()},
                  **{_TABLE_PREFIX + name: dtype for name, dtype in TABLE_TYPES.items()},
                  **{_AREA: _AREA_TYPE})
    n_links = len(listing) - len(FIELD_TYPES) - len(others) if isinstance(listing, dict) else 0
    types = dict(FIELD_TYPES, **others, **{f"links_{k}": _LINK_TYPE for k in range(n_links)})
    if n_links < 1 or set(listing) != set(types):
        raise InvalidInputError("header.json lists other arrays than a roadmap's, its "
                                "segmentation's and its index's")
    for name, spec in listing.items():
        if (not isinstance(spec, dict) or set(spec) != {"dtype", "shape", "crc32"}
                or spec["dtype"] != np.dtype(types[name]).str
                or not isinstance(spec["shape"], list)
                or not all(type(n) is int and n >= 0 for n in spec["shape"])
                or type(spec["crc32"]) is not int):
            raise InvalidInputError(f"header.json lists {name} wrongly")


def _check_names(header, mechanism, grid, refinement, thin_refinement):
    """That an entry's header names the mechanism and grid asked for: the
    grid, or it refined (by :func:`refine`, or around its thin regions)."""
    if _checksum(header["mechanism"]) != _checksum(mechanism.to_dict()):
        raise InvalidInputError("header.json names another mechanism")
    stored = header["grid"]
    refined = (isinstance(stored, dict) and stored.get("kind") == "adaptive"
               and stored.get("refinement") == (thin_refinement if refinement is None
                                                else refinement)
               and _checksum(stored.get("base")) == _checksum(grid.to_dict()))
    if refinement is None:
        same = (_checksum(stored) == _checksum(grid.to_dict())
                or (thin_refinement is not None and refined))
    else:
        same = refined
    if not same:
        raise InvalidInputError("header.json names another grid")


def _read(folder, name, spec, verify=True):
    """An array of an entry, mapped copy on write (module doc) and checked
    against its header ``spec``: its dtype, shape and size, and its checksum
    when ``verify``."""
    with open(os.path.join(folder, name + ".npy"), "rb") as stream:
        version = np.lib.format.read_magic(stream)
        writers = {(1, 0): np.lib.format.write_array_header_1_0,
                   (2, 0): np.lib.format.write_array_header_2_0}
        if version not in writers:
            raise InvalidInputError(f"{name}.npy has .npy version {version}")
        # The file's header is compared with the one np.save writes for the
        # listed dtype and shape, not parsed: numpy parses it with the ast
        # module, whose bookkeeping on Python 3.11 (CPython gh-106905) raises
        # SystemError at random when several threads parse at once.
        dtype, shape = np.dtype(spec["dtype"]), tuple(spec["shape"])
        expected = io.BytesIO()
        writers[version](expected, {"descr": np.lib.format.dtype_to_descr(dtype),
                                    "fortran_order": False, "shape": shape})
        expected = expected.getvalue()
        stream.seek(0)
        if stream.read(len(expected)) != expected:
            raise InvalidInputError(f"{name}.npy's header is not that of the {spec['dtype']} "
                                    f"{shape} array the entry's header lists")
        size = dtype.itemsize * math.prod(shape)
        # Sized before mapping, so a wrong header never maps past the file's end.
        if os.fstat(stream.fileno()).st_size - stream.tell() != size:
            raise InvalidInputError(f"{name}.npy is not {size} bytes of data")
        if size == 0:
            array = np.empty(shape, dtype)
        else:
            # A plain ndarray on the mapping (which it keeps open): compiled
            # kernels are typed for plain, writable arrays.
            array = np.memmap(stream, dtype, mode="c", offset=stream.tell(),
                              shape=shape).view(np.ndarray)
    if verify and _checksum(array) != spec["crc32"]:
        raise InvalidInputError(f"{name}.npy fails its checksum")
    return array


def _check_values(mechanism, grid, arrays):
    """The value ranges of an entry's arrays (module doc)."""
    slots, pose_size = mechanism.max_solutions, mechanism.pose_size
    count, poses, margin = arrays["count"], arrays["poses"], arrays["margin"]
    region, patch = arrays["region"], arrays["patch"]
    n = grid.size
    shapes = {"count": (n,), "poses": (n, slots, pose_size), "margin": (n, slots),
              "region": (n,), "patch": (n, slots)}
    if any(arrays[name].shape != shape for name, shape in shapes.items()):
        raise InvalidInputError("the arrays' shapes do not fit the mechanism and each other")
    if count.max(initial=0) > slots:
        raise InvalidInputError(f"solution counts exceed the mechanism's {slots}")
    valid = np.arange(slots) < count[:, None]
    if not np.array_equal(np.isfinite(margin), valid):
        raise InvalidInputError("margins are not finite exactly where a solution exists")
    # A NaN or an infinity in any coordinate makes the sum non-finite; summed
    # coordinate by coordinate, five times faster than reducing the short
    # axis, and in chunks: temporaries the size of the poses would cost more
    # in fresh pages than the sums.
    for start in range(0, n, _POSE_CHUNK):
        part = poses[start:start + _POSE_CHUNK]
        if not np.array_equal(np.isfinite(sum(part[..., k] for k in range(pose_size))),
                              valid[start:start + _POSE_CHUNK]):
            raise InvalidInputError("poses are not finite exactly where a solution exists")
    if region.min(initial=0) < 0 or region[count == 0].any():
        raise InvalidInputError("region ids are negative or on cells without solutions")
    if patch[~valid].any():
        raise InvalidInputError("patch ids on solutions that do not exist")
    # A sample, spread over the cells and their slots: all of them would cost
    # a third of a second on the full roadmap, and the checksums already
    # cover every byte.
    solved = np.flatnonzero(count)
    cells = solved[np.linspace(0, solved.size - 1, min(solved.size, _MARGIN_SAMPLES),
                               dtype=np.int64)]
    sample = (cells, np.arange(cells.size) % count[cells])
    joints = np.empty((cells.size, mechanism.n_joints))
    joints[:, list(grid.axis_joints)] = grid.coordinates_of(cells)
    for joint, value in grid.fixed:
        joints[:, joint] = value
    if not np.allclose(mechanism.margin(poses[sample], joints), margin[sample], rtol=1e-6,
                       atol=1e-9):
        raise InvalidInputError("margins differ from the margins of their poses")


def _discard(path):
    """Remove an entry, renamed first so that a reader finds it whole or not at all."""
    trash = f"{path}.{os.urandom(4).hex()}.tmp"
    try:
        os.rename(path, trash)
    except OSError:  # removed meanwhile, or the cache is read-only
        return
    shutil.rmtree(trash, ignore_errors=True)


def _folder_bytes(path):
    with os.scandir(path) as items:
        return sum(item.stat(follow_symlinks=False).st_size for item in items)


def _evict(directory, keep, max_bytes):
    """Remove least recently used entries but ``keep`` until the entries total
    at most ``max_bytes``, and abandoned staging folders (module doc)."""
    now = time.time()
    entries, total = [], 0
    try:
        with os.scandir(directory) as items:
            items = list(items)
    except OSError:
        return
    for item in items:
        try:
            if not item.is_dir(follow_symlinks=False):
                continue
            if _STAGING_NAME.fullmatch(item.name):
                if now - item.stat(follow_symlinks=False).st_mtime > STALE_STAGING_SECONDS:
                    shutil.rmtree(item.path, ignore_errors=True)
                continue
            if not _ENTRY_NAME.fullmatch(item.name):
                continue
            used, size = item.stat(follow_symlinks=False).st_mtime, _folder_bytes(item.path)
        except OSError:  # removed by another process meanwhile
            continue
        total += size
        if item.path != keep:
            entries.append((used, item.path, size))
    for _, path, size in sorted(entries):
        if total <= max_bytes:
            break
        _discard(path)
        total -= size
