"""Position problems (seed 003): forward kinematics by screw continuation, assembly
modes, iterative inverse kinematics (work in progress: see issue 4)."""

from __future__ import annotations


class PositionMixin:
    """Forward and inverse position problems of a :class:`~pkm_pin.Mechanism`."""
