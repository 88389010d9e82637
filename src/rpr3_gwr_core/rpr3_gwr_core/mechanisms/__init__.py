"""Mechanisms: the interface the roadmap and the planner use, the 3-RPR,
the five-bar, the 3-RRR and the 3-PRR."""

import importlib

from ..lazy import lazy_exports
from . import base
from .base import Mechanism, register_mechanism

# Each mechanism's module is loaded on first use of one of its names or
# documents (PEP 562): it loads its compiled kernels, which a process
# working with another mechanism does not need.
_MODULES = {
    ".rpr3": ("3-RPR", ("ThreeRPR", "PAPER_GEOMETRY")),
    ".five_bar": ("5R", ("FiveBar", "DEFAULT_FIVE_BAR")),
    ".rrr3": ("3-RRR", ("ThreeRRR", "DEFAULT_THREE_RRR")),
    ".prr3": ("3-PRR", ("ThreePRR", "DEFAULT_THREE_PRR")),
}
_MODULE_OF_NAME = {name: module for module, (_, names) in _MODULES.items() for name in names}
_MODULE_OF_KIND = {kind: module for module, (kind, _) in _MODULES.items()}

__all__ = ["Mechanism", "mechanism_class", "mechanism_from_dict", "register_mechanism",
           *_MODULE_OF_NAME]


def mechanism_class(kind):
    """The class of a mechanism kind (:func:`.base.mechanism_class`), its
    module loaded first.

    Raises
    ------
    InvalidInputError
        If the kind is unknown.
    """
    # An unknown kind loads them all, so that the error lists every kind.
    known = isinstance(kind, str) and kind in _MODULE_OF_KIND
    for module in [_MODULE_OF_KIND[kind]] if known else _MODULES:
        importlib.import_module(module, __name__)
    return base.mechanism_class(kind)


def mechanism_from_dict(data):
    """Rebuild a mechanism from :meth:`Mechanism.to_dict`'s plain data
    (:func:`.base.mechanism_from_dict`), its module loaded first.

    Raises
    ------
    InvalidInputError
        If the data names no known kind or its parameters are invalid.
    """
    kind = data.get("kind") if isinstance(data, dict) else None
    return mechanism_class(kind).from_dict(data)


__getattr__, __dir__ = lazy_exports(__name__, globals(), _MODULE_OF_NAME)
