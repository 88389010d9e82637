"""The bounds the ``rpr3-gwr`` tool puts on the numbers it takes; standard
library only, so that the command line checks its arguments without loading
the core."""

__all__ = ["MAX_LEG"]

# The direct kinematics weighs the squared legs against the geometry's tens
# of units, so the leg residual of its solutions grows with them (3e-7 at
# 1e6, 4e-3 at 1e10) until its polynomial overflows near 1e77.
MAX_LEG = 1e6
"""Longest leg, and farthest position, the tool takes [length unit]."""
