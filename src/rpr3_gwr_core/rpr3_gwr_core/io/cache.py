"""An on-disk cache of built roadmaps, keyed by mechanism, grid and format.

The only module of the core that touches the file system: the CLI and the
nodes use it so that a second call with the same mechanism and grid loads the
roadmap instead of rebuilding it.  An entry is a folder of ``.npy`` files,
one per array of :func:`~rpr3_gwr_core.io.export.roadmap_arrays`, with the
mechanism and grid documents in ``header.json``, written to a temporary
folder and renamed into place: the full 3-DOF roadmap's arrays (about
400 MB) load in a tenth of a second from the page cache, without the
checksums and copies of a zip archive.
"""

import hashlib
import json
import os
import shutil
import tempfile
import time

import numpy as np

from ..exceptions import InvalidInputError
from ..workspace import build_roadmap, refine
from .export import FORMAT, VERSION, roadmap_arrays, roadmap_from_arrays

__all__ = ["default_cache_dir", "cache_key", "cached_roadmap"]

# Bump when a change of the algorithms changes roadmaps, so old entries are not reused.
ALGORITHM_REVISION = 4


def default_cache_dir():
    """``$RPR3_GWR_CACHE``, else ``$XDG_CACHE_HOME/rpr3-gwr``, else ``~/.cache/rpr3-gwr``."""
    if os.environ.get("RPR3_GWR_CACHE"):
        return os.environ["RPR3_GWR_CACHE"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "rpr3-gwr")


def cache_key(mechanism, grid, method="components", min_region_cells=8, refinement=None):
    """Hex digest identifying a roadmap build."""
    text = json.dumps({"format": FORMAT, "version": VERSION, "revision": ALGORITHM_REVISION,
                       "mechanism": mechanism.to_dict(), "grid": grid.to_dict(),
                       "method": method, "min_region_cells": min_region_cells,
                       "refinement": refinement}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_roadmap(mechanism, grid, cache_dir=None, progress=None, refinement=None):
    """Load a roadmap from the cache, or build and store it.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid
    cache_dir : str, optional
        Defaults to :func:`default_cache_dir`.
    progress : callable, optional
        Passed to :func:`~rpr3_gwr_core.roadmap.build_roadmap`.
    refinement : int, optional
        Build on ``refine(mechanism, grid, refinement)`` (an adaptive grid)
        instead of ``grid`` itself.

    Returns
    -------
    roadmap : Roadmap
    hit : bool
        Whether it came from the cache.
    """
    directory = cache_dir or default_cache_dir()
    path = os.path.join(directory, cache_key(mechanism, grid, refinement=refinement))
    if os.path.isdir(path):
        try:
            return _load(path), True
        except (InvalidInputError, OSError, ValueError, KeyError):
            shutil.rmtree(path, ignore_errors=True)  # a damaged entry is rebuilt below
    begin = time.perf_counter()
    if refinement is not None:
        grid = refine(mechanism, grid, refinement)
    refined = time.perf_counter() - begin
    roadmap = build_roadmap(mechanism, grid, progress=progress)
    if refinement is not None:
        roadmap.timings["refine"] = refined
    os.makedirs(directory, exist_ok=True)
    staging = tempfile.mkdtemp(dir=directory, suffix=".tmp")
    _save(staging, roadmap)
    try:
        os.rename(staging, path)
    except OSError:  # another process stored the same entry meanwhile
        shutil.rmtree(staging, ignore_errors=True)
    return roadmap, False


def _save(folder, roadmap):
    arrays = roadmap_arrays(roadmap)
    links = arrays.pop("links")
    header = {"mechanism": roadmap.mechanism.to_dict(), "grid": roadmap.grid.to_dict(),
              "arrays": sorted(arrays), "axes": len(links)}
    arrays.update({f"links_{k}": match for k, match in enumerate(links)})
    for name, array in arrays.items():
        np.save(os.path.join(folder, name + ".npy"), array)
    with open(os.path.join(folder, "header.json"), "w", encoding="utf-8") as stream:
        json.dump(header, stream)


def _load(folder):
    with open(os.path.join(folder, "header.json"), encoding="utf-8") as stream:
        header = json.load(stream)

    def read(name):
        return np.load(os.path.join(folder, name + ".npy"), allow_pickle=False)

    arrays = {name: read(name) for name in header["arrays"]}
    arrays["links"] = [read(f"links_{k}") for k in range(header["axes"])]
    return roadmap_from_arrays(header["mechanism"], header["grid"], arrays)
