"""Serial-chain kinematics of a leg (placeholder module, filled by the serial-chain work)."""

from __future__ import annotations


class SerialChainMixin:
    """Link screws, point velocities/accelerations and the serial Jacobian of a Leg."""
