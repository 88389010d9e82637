"""Lazy exports of a package (PEP 562): each name is imported from its
module on first use and kept in the package's namespace."""

import importlib

__all__ = ["lazy_exports"]


def lazy_exports(package, namespace, module_of):
    """The ``__getattr__`` and ``__dir__`` of a package whose names
    ``module_of`` (name to relative module) are loaded on first use.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    namespace : dict
        Its ``globals()``, where a loaded name is kept.
    module_of : mapping of str to str
        For each lazy name, the module (relative to ``package``) that defines it.

    Returns
    -------
    (callable, callable)
    """
    def __getattr__(name):  # noqa: N807 (the module hook's name)
        if name not in module_of:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module_of[name], package), name)
        namespace[name] = value
        return value

    def __dir__():  # noqa: N807
        return sorted(set(namespace) | set(module_of))

    return __getattr__, __dir__
