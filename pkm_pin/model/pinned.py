"""Legs that meet at a pin instead of a rigid platform, as one closure model.

A planar five-bar (two legs joined by a revolute at their distal ends) or a Delta whose
"platform" is a point (three legs ending in spherical joints at one point) has no
platform body: the legs meet at a **pin**. :func:`pinned_legs` writes such a mechanism as
the general :class:`~pkm_pin.model.closure_model.ClosureModel`:

* the tree: every leg appended under the universe at its base placement, its joint and
  frame names prefixed ``"legname/"`` (as :func:`~.closure_model.from_mechanism`);
* the pin frame :data:`PIN`: a frame on the first leg's last joint, at
  ``tip_0 · anchor_0⁻¹``;
* one closure per other leg ``i`` between :data:`PIN` and the constraint frame
  ``tip_i · anchor_i⁻¹``, of kind ``"point"`` (a spherical pin: the origins coincide) or
  ``"revolute"`` (a revolute pin: the origins and the z axes coincide);
* actuated: ``"leg/joint"``; output: the point :data:`PIN` (``output_point``: its
  translations are analysed, not the turning of the first leg's last link); reference
  configuration: the legs' home configurations (neutral where none is given).

``anchor_i`` is, as for a platform, the placement of leg ``i``'s tip frame in the pin
frame; with a spherical pin only its translation matters, with a revolute pin the pin's
axis is the z axis of ``tip_i · anchor_i⁻¹``. Identity anchors: the tip frames are the
pin (their z axes are the revolute's axis).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .closure_model import Closure, ClosureModel, _prefixed

#: Name of the pin's frame (the output of a pinned mechanism).
PIN = "pin"

#: Pin kinds of a mechanism file (``closure = ...``) and the closure each one writes.
PIN_KINDS = {"spherical": "point", "revolute": "revolute"}


def pinned_legs(legs: Sequence, anchors: Sequence[pin.SE3] | None, kind: str, *,
                name: str = "", home_q: Sequence | None = None) -> ClosureModel:
    """The closure model of ``legs`` (:class:`~pkm_pin.Leg`) meeting at one pin.

    Args:
        legs: At least two legs with distinct names.
        anchors: Each leg's tip frame in the pin frame (identity when ``None``).
        kind: ``"spherical"`` or ``"revolute"`` (:data:`PIN_KINDS`).
        name: Name of the mechanism.
        home_q: Optional configuration of each leg (``None`` entries: neutral); together
            the reference configuration assembly starts from.
    """
    legs = list(legs)
    if kind not in PIN_KINDS:
        raise InputError(f"unknown pin {kind!r}: a pin is one of {sorted(PIN_KINDS)} "
                         "(a rigid platform is a weld: pkm_pin.Mechanism)")
    if len(legs) < 2:
        raise InputError(f"a pin joins at least two legs, got {len(legs)}")
    anchors = [pin.SE3.Identity()] * len(legs) if anchors is None else list(anchors)
    if len(anchors) != len(legs):
        raise InputError(f"{len(anchors)} anchors given for {len(legs)} legs")
    home_q = [None] * len(legs) if home_q is None else list(home_q)
    if len(home_q) != len(legs):
        raise InputError(f"home_q has {len(home_q)} entries for {len(legs)} legs")
    tree = pin.Model()
    tree.name = name
    for leg in legs:
        tree = pin.appendModel(tree, _prefixed(leg.model, leg.name), 0, leg.base)
    first = legs[0]
    tip = tree.frames[tree.getFrameId(f"{first.name}/{first.tip}")]
    tree.addFrame(pin.Frame(PIN, tip.parentJoint, tip.parentFrame,
                            tip.placement * anchors[0].inverse(), pin.FrameType.OP_FRAME))
    closures = tuple(Closure(PIN_KINDS[kind], PIN, f"{leg.name}/{leg.tip}", pin.SE3.Identity(),
                             anchor.inverse(), name=f"{first.name}-{leg.name}")
                     for leg, anchor in zip(legs[1:], anchors[1:]))
    reference = np.concatenate([pin.neutral(leg.model) if q is None else
                                leg.check_q(q, f"home_q of leg {leg.name!r}")
                                for leg, q in zip(legs, home_q)])
    actuated = tuple(f"{leg.name}/{a}" for leg in legs for a in leg.actuated)
    return ClosureModel(tree, closures, actuated, PIN, name, reference=reference,
                        output_point=True)
