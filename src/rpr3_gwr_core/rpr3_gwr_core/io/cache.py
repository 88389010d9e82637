"""An on-disk cache of built roadmaps, keyed by mechanism, grid and format.

The only module of the core that touches the file system: the CLI and the
nodes use it so that a second call with the same mechanism and grid loads the
roadmap instead of rebuilding it.  Entries are the JSON of
:func:`~rpr3_gwr_core.export.roadmap_to_json`, written atomically.
"""

import hashlib
import json
import os
import tempfile

from ..exceptions import InvalidInputError
from ..workspace import build_roadmap
from .export import FORMAT, VERSION, roadmap_from_json, roadmap_to_json

__all__ = ["default_cache_dir", "cache_key", "cached_roadmap"]

# Bump when a change of the algorithms changes roadmaps, so old entries are not reused.
ALGORITHM_REVISION = 2


def default_cache_dir():
    """``$RPR3_GWR_CACHE``, else ``$XDG_CACHE_HOME/rpr3-gwr``, else ``~/.cache/rpr3-gwr``."""
    if os.environ.get("RPR3_GWR_CACHE"):
        return os.environ["RPR3_GWR_CACHE"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "rpr3-gwr")


def cache_key(mechanism, grid, method="components", min_region_cells=8):
    """Hex digest identifying a roadmap build."""
    text = json.dumps({"format": FORMAT, "version": VERSION, "revision": ALGORITHM_REVISION,
                       "mechanism": mechanism.to_dict(), "grid": grid.to_dict(),
                       "method": method, "min_region_cells": min_region_cells}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_roadmap(mechanism, grid, cache_dir=None, progress=None):
    """Load a roadmap from the cache, or build and store it.

    Parameters
    ----------
    mechanism : Mechanism
    grid : Grid
    cache_dir : str, optional
        Defaults to :func:`default_cache_dir`.
    progress : callable, optional
        Passed to :func:`~rpr3_gwr_core.roadmap.build_roadmap`.

    Returns
    -------
    roadmap : Roadmap
    hit : bool
        Whether it came from the cache.
    """
    directory = cache_dir or default_cache_dir()
    path = os.path.join(directory, cache_key(mechanism, grid) + ".json")
    if os.path.exists(path):
        try:
            with open(path, encoding="utf-8") as stream:
                return roadmap_from_json(stream.read()), True
        except InvalidInputError:
            pass  # a damaged entry is rebuilt below
    roadmap = build_roadmap(mechanism, grid, progress=progress)
    os.makedirs(directory, exist_ok=True)
    handle, tmp = tempfile.mkstemp(dir=directory, suffix=".tmp")
    with os.fdopen(handle, "w", encoding="utf-8") as stream:
        stream.write(roadmap_to_json(roadmap))
    os.replace(tmp, path)
    return roadmap, False
