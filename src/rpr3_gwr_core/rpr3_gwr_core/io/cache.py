"""An on-disk cache of built roadmaps, keyed by mechanism, grid and format.

The only module of the core that touches the file system: the CLI and the
nodes use it so that a second call with the same mechanism and grid loads the
roadmap instead of rebuilding it.  Entries are numpy ``.npz`` archives of
:func:`~rpr3_gwr_core.io.export.roadmap_arrays` with the mechanism and grid
documents, written atomically: the full 3-DOF roadmap's arrays (about
300 MB) load in a fraction of the time their JSON would take.
"""

import hashlib
import json
import os
import tempfile
import time
import zipfile

import numpy as np

from ..exceptions import InvalidInputError
from ..workspace import build_roadmap, refine
from .export import FORMAT, VERSION, roadmap_arrays, roadmap_from_arrays

__all__ = ["default_cache_dir", "cache_key", "cached_roadmap"]

# Bump when a change of the algorithms changes roadmaps, so old entries are not reused.
ALGORITHM_REVISION = 3


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
    path = os.path.join(directory, cache_key(mechanism, grid, refinement=refinement) + ".npz")
    if os.path.exists(path):
        try:
            return _load(path), True
        except (InvalidInputError, OSError, ValueError, KeyError, zipfile.BadZipFile):
            pass  # a damaged entry is rebuilt below
    begin = time.perf_counter()
    if refinement is not None:
        grid = refine(mechanism, grid, refinement)
    refined = time.perf_counter() - begin
    roadmap = build_roadmap(mechanism, grid, progress=progress)
    if refinement is not None:
        roadmap.timings["refine"] = refined
    os.makedirs(directory, exist_ok=True)
    handle, tmp = tempfile.mkstemp(dir=directory, suffix=".npz")
    with os.fdopen(handle, "wb") as stream:
        _save(stream, roadmap)
    os.replace(tmp, path)
    return roadmap, False


def _save(stream, roadmap):
    arrays = roadmap_arrays(roadmap)
    header = {"mechanism": roadmap.mechanism.to_dict(), "grid": roadmap.grid.to_dict(),
              "axes": len(arrays["links"])}
    links = {f"links_{k}": match for k, match in enumerate(arrays.pop("links"))}
    np.savez(stream, header=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8),
             **arrays, **links)


def _load(path):
    with np.load(path) as archive:
        header = json.loads(archive["header"].tobytes().decode())
        arrays = {name: archive[name] for name in archive.files
                  if name != "header" and not name.startswith("links_")}
        arrays["links"] = [archive[f"links_{k}"] for k in range(header["axes"])]
    return roadmap_from_arrays(header["mechanism"], header["grid"], arrays)
