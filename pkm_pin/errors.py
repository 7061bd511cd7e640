"""Exceptions of pkm_pin.

Every error a user can provoke is a :class:`PkmError`. Subclasses carry the data
that describes the problem and build a message that says what was wrong, where,
and how to fix it. Errors raised by Pinocchio, yourdfpy or the XML parser are
re-raised as one of these, chained with ``raise ... from``.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

#: Longest echo of a value from an input in an error message [characters]: a hostile
#: file's 10 MB value must not become a 10 MB error line.
MAX_ECHO = 300


def _cut(value, limit: int = MAX_ECHO) -> str:
    """``repr(value)`` cut to ``limit`` characters, ending with "…" when cut."""
    text = repr(value) if not isinstance(value, str) or len(value) <= 4 * limit \
        else repr(value[:4 * limit])
    return text if len(text) <= limit else text[:limit - 1] + "…"


def _clip(text: str, limit: int = MAX_ECHO) -> str:
    """``text`` (a path, a label) cut to ``limit`` characters, ending with "…" when cut."""
    return text if len(text) <= limit else text[:limit - 1] + "…"


def _is_file(path) -> bool:
    """``Path.is_file()``, False for names the OS refuses (too long, a NUL byte)."""
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def _listing(names: Iterable[str], limit: int = 25) -> str:
    """Comma-separated, quoted list of names (each cut by :func:`_cut`), cut after
    ``limit`` entries."""
    names = list(names)
    shown = ", ".join(_cut(n) for n in names[:limit])
    if len(names) > limit:
        shown += f", … ({len(names) - limit} more)"
    return shown or "(none)"


class PkmError(Exception):
    """Base class of every error raised by pkm_pin.

    Pickling (an error raised in a worker process of a sweep comes back to the parent
    pickled) keeps the class, ``args`` (the message) and every attribute, without
    calling ``__init__`` again: the errors whose ``__init__`` builds the message from
    other arguments (:class:`AssemblyError`,
    :class:`~pkm_pin.linkage.LoopClosureError`: loop, residual, q, diagnosis) could not
    be rebuilt from their message by the default reduction."""

    def __reduce__(self):
        return _rebuilt, (type(self), self.args, self.__dict__.copy())


def _rebuilt(cls, args: tuple, state: dict) -> PkmError:
    """The error of class ``cls`` with these ``args`` and attributes
    (:meth:`PkmError.__reduce__`)."""
    error = cls.__new__(cls, *args)
    error.args = args
    error.__dict__.update(state)
    return error


class InputError(PkmError, ValueError):
    """An argument of an API call has the wrong shape, type or value."""


class UrdfError(PkmError):
    """A URDF cannot be read, parsed or turned into a kinematic model.

    Attributes:
        source: File path or a short description of the XML string.
        reason: What is wrong.
    """

    def __init__(self, source: str, reason: str, hint: str = ""):
        self.source = source
        self.reason = reason
        self.hint = hint
        message = f"URDF {source}: {reason}"
        if hint:
            message += f". {hint}"
        super().__init__(message)


class FrameNotFound(PkmError, KeyError):
    """A frame (link or named frame) is not in the model.

    Attributes:
        name: The frame that was asked for.
        frames: The frames that exist.
        where: Which model was searched.
    """

    def __init__(self, name: str, frames: Sequence[str], where: str = "the model"):
        self.name = name
        self.frames = list(frames)
        self.where = where
        super().__init__(name)

    def __str__(self) -> str:
        return (
            f"frame {self.name!r} is not a link or frame of {self.where}; "
            f"the frames are: {_listing(self.frames)}"
        )


class JointNotFound(PkmError, KeyError):
    """A joint is not a movable joint where one was expected.

    Attributes:
        name: The joint that was asked for.
        joints: The joints that would have been valid.
        where: Which model or chain was searched.
    """

    def __init__(self, name: str, joints: Sequence[str], where: str = "the model"):
        self.name = name
        self.joints = list(joints)
        self.where = where
        super().__init__(name)

    def __str__(self) -> str:
        return (
            f"joint {self.name!r} is not a movable joint of {self.where}; "
            f"the movable joints are: {_listing(self.joints)}"
        )


class TreeFrameNotFound(FrameNotFound, InputError):
    """A closure or the output of a closure model names a frame that is not in its tree."""


class TreeJointNotFound(JointNotFound, InputError):
    """An actuated name of a closure model is not a movable joint of its tree."""


class MechanismFileError(PkmError):
    """A mechanism (TOML) file is wrong.

    Attributes:
        path: The file.
        where: The table or key in the file (e.g. ``legs[2].actuated``).
        reason: What is wrong and how to fix it.
    """

    def __init__(self, path: str, where: str, reason: str):
        self.path = path
        self.where = where
        self.reason = reason
        location = f"{path}" + (f", {where}" if where else "")
        super().__init__(f"{location}: {reason}")


class AssemblyError(PkmError):
    """A leg cannot reach the pose asked of it.

    Attributes:
        leg: Name of the leg.
        residual: Remaining pose error of the leg's best attempt (norm of the log6
            error, angular part in rad and linear part divided by the characteristic
            length); nan when no attempt measures it (the ``detail`` then is the whole
            reason, and the message prints no nan).
    """

    def __init__(self, leg: str, residual: float, detail: str = ""):
        self.leg = leg
        self.residual = float(residual)
        if not math.isfinite(self.residual):
            who = "the output" if leg == "output pose" else f"leg {leg!r}"
            message = f"{who} cannot reach the pose" + (f": {detail}" if detail else "")
        else:
            message = (
                f"leg {leg!r} cannot reach the pose: the best configuration found within "
                f"the joint limits leaves a relative pose error of {self.residual:.3g}"
            )
            if detail:
                message += f" ({detail})"
        super().__init__(message)


class InvalidAssembly(InputError):
    """An :class:`~pkm_pin.Assembly` made by hand is not one: a leg does not close on the
    platform pose, or a joint is outside its limits."""


class SingularityError(PkmError):
    """A velocity map was asked for at or too close to a singular configuration.

    Attributes:
        kind: Which map ("forward", "inverse", ...).
        index: The closeness index that was below the threshold.
    """

    def __init__(self, message: str, kind: str = "", index: float = float("nan")):
        self.kind = kind
        self.index = index
        super().__init__(message)


class ForwardKinematicsError(PkmError):
    """The forward position problem did not converge to a valid assembly."""

    def __init__(self, message: str, reached=None):
        self.reached = reached
        super().__init__(message)


class ClosureFileError(MechanismFileError):
    """A closed-loop description (Extended-URDF closures YAML/TOML, or an MJCF file with
    ``<equality>`` closures) is wrong.

    Attributes:
        path: The file.
        where: The key or element in the file (e.g. ``closed_loop[1][0]``,
            ``equality/connect[2]``).
        reason: What is wrong and how to fix it.
    """


class InconsistentMotion(InputError):
    """A motion given to the inverse dynamics (:mod:`pkm_pin.dynamics`) is not one the
    mechanism can make.

    Attributes:
        kind: ``"velocity"`` (``J v ≠ 0``), ``"acceleration"`` (``J a + J̇ v ≠ 0``) or
            ``"idle"`` (a generalized force along an idle motion that no actuator gives).
        residual: The closure rows' residual [physical units] (velocity, acceleration),
            or the unbalanced generalized force per velocity coordinate (idle).
        joints: The joints that move in the idle motion (``"idle"``), else empty.
    """

    def __init__(self, message: str, kind: str = "", residual=None, joints: tuple = ()):
        self.kind = kind
        self.residual = residual
        self.joints = tuple(joints)
        super().__init__(message)


class SimulationError(PkmError):
    """A forward-dynamics simulation (:mod:`pkm_pin.simulation`) cannot continue: a
    non-finite acceleration, a singular constrained system."""


class InertiaError(InputError):
    """A body's mass or inertia cannot be a rigid body's: read where the dynamics uses
    them (:mod:`pkm_pin.dynamics`).

    Attributes:
        body: The body (its URDF link / MJCF body, else its joint).
        quantity: ``"mass"`` or ``"inertia"``.
        value: The offending value: the mass [kg], or the inertia about the centre of
            mass (3 × 3) [kg m²].
        reason: What is wrong with it.
    """

    def __init__(self, body: str, quantity: str, value, reason: str, shown: str = ""):
        self.body = body
        self.quantity = quantity
        self.value = value
        self.reason = reason
        super().__init__(
            f"body {_cut(body)}: {quantity} {shown or value} {reason}; fix the body's inertial "
            "data in the model file (URDF <inertial>, MJCF <inertial> or its geoms), or "
            "give it mass 0 and no inertia to make it massless")
