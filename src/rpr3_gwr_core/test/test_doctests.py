"""The Examples sections of the main entry points run as written."""

import doctest
import importlib

import pytest

MODULES = ["rpr3_gwr_core", "rpr3_gwr_core.paper", "rpr3_gwr_core.workspace.field",
           "rpr3_gwr_core.workspace.roadmap", "rpr3_gwr_core.workspace.adaptive"]


@pytest.mark.parametrize("name", MODULES)
def test_examples_run(name):
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
