"""Where the tool keeps its files; standard library only, so that the
command line can show its defaults without loading the core."""

import os

__all__ = ["default_cache_dir"]


def default_cache_dir():
    """``$RPR3_GWR_CACHE``, else ``$XDG_CACHE_HOME/rpr3-gwr``, else ``~/.cache/rpr3-gwr``."""
    if os.environ.get("RPR3_GWR_CACHE"):
        return os.environ["RPR3_GWR_CACHE"]
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "rpr3-gwr")
