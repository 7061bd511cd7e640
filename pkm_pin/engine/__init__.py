"""The analysis engine: the screw algebra of N ≥ 1 assembled poses in compiled code.

See :mod:`.core` (the loop over poses, :class:`Layout`, :class:`Results`),
:mod:`.stages` (one stage per concept: motion twists, leg constraints, actuation
wrenches, platform twist system, indices) and :mod:`.linalg` (Jacobi SVD, determinant).
"""

from .core import Layout, Results, allocate, analyse, analyse_into

__all__ = ["Layout", "Results", "allocate", "analyse", "analyse_into"]
