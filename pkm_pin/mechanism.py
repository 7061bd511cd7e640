"""Mechanisms (legs joined by a platform), their description files, and assemblies.

A :class:`Mechanism` is a list of :class:`~pkm_pin.leg.Leg` whose tips are fixed to one
platform: the tip frame of leg ``i`` coincides with ``pose * anchors[i]`` where ``pose``
is the platform placement in the world. An :class:`Assembly` is one solution of those
closure equations: the platform pose and one configuration per leg.

Mechanism files (TOML legs, Extended URDF, MJCF) are read by
:func:`pkm_pin.io.load_mechanism`; :meth:`Mechanism.from_closure_model` builds the legs of
a base–legs–platform machine detected in any closure model.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor
from functools import cached_property

import numpy as np
import pinocchio as pin

from . import dynamics as _dynamics
from . import position
from . import sensitivity as _sensitivity
from . import sweep as _sweep
from .analysis import Analysis, layout_of
from .assembly import Assembly, as_pose, placement
from .compiling import prefer_compiled
from .engine import Layout
from .errors import (
    AssemblyError,
    InputError,
    PkmError,
)
from .leg import Leg
from .linkage import Linkage, LoopClosureError
from .model.chain_urdf import chain_urdf
from .screws import as_fraction, as_vector, homogenise
from .solve import (
    LEGS,
    POSE_COORDINATES,
    iter_tree_starts,
    solve_kernel,
    solve_system,
    solve_tree_starts,
)
from .tolerances import (
    CLOSENESS_SINGULAR_TOL,
    CLOSURE_TOL,
    INERTIA_TOL,
    JOINT_LIMIT_SLACK,
    TYPE_I_CLOSURE_TOL,
    TYPE_I_STALL_FACTOR,
)
from .twists import LegFrames, TreePass, has_mimic, leg_frames, verified_twists

#: The backends of a :class:`Mechanism` (:attr:`Mechanism.backend`).
BACKENDS = ("legs", "general")


class Mechanism:
    """A closed-loop mechanism, whatever file it came from: one closure model (a
    Pinocchio tree plus closures, :attr:`model`) read by one of two backends
    (:attr:`backend`):

    * ``"legs"``: a base–legs–platform machine (legs whose tips are fixed to one
      platform), given as legs (TOML) or detected in any closure model
      (:meth:`from_closure_model`), analysed leg by leg with seed 000's screws and the
      compiled per-leg engine;
    * ``"general"``: any closure model (:meth:`from_model`: an Extended URDF, MJCF,
      legs meeting at a pin …), read by the general elimination
      (:class:`~pkm_pin.linkage.Linkage`, :attr:`general`); where a platform structure is
      detected in it the capabilities that read a machine leg by leg (sensitivity, every
      working mode, the Study homotopy, partial poses) use its per-leg reading
      (:attr:`legs_mechanism`).

    Every mechanism answers the same names; those of one backend only are answered on the
    other through :attr:`general` (mobility, idle motions, transmission over the tree,
    sub-mechanisms) or :attr:`legs_mechanism`, or refused with the reason.

    The per-leg backend:

    The description (legs, anchors, home) is set once; what is computed from it is
    cached in the properties declared below (:attr:`characteristic_length`,
    :attr:`actuated_scales`, :attr:`home_assembly`, :attr:`home_analysis`, :attr:`kernel`).
    The position problems, the sensitivity and the sweeps are functions of
    :mod:`pkm_pin.position`, :mod:`pkm_pin.sensitivity` and :mod:`pkm_pin.sweep` taking
    the mechanism first; the methods of the same names call them.

    Args:
        legs: The legs; their names must be distinct.
        anchors: Placement of each leg's tip frame in the platform frame (identity by
            default).
        name: Name of the mechanism.
        home: A platform pose where the mechanism assembles (identity by default).
        home_q: Optional leg configurations at home, selecting the working mode.
        description: One line saying what it is.
        length_unit: The unit the URDFs' lengths are written in (``"m"`` as URDF
            specifies; ``"mm"`` for a model written in millimetres): reports label
            lengths with it. Nothing is converted: pkm_pin's results are in the model's
            own unit, and every index and rank decision is unit-invariant.
    """

    #: Which backend answers: ``"legs"`` here, ``"general"`` for a mechanism made by
    #: :meth:`from_model` (:data:`BACKENDS`).
    backend = "legs"

    def __init__(
        self,
        legs: Sequence[Leg],
        anchors: Sequence[pin.SE3] | None = None,
        name: str = "mechanism",
        home: pin.SE3 | None = None,
        home_q: Sequence | None = None,
        description: str = "",
        length_unit: str = "m",
    ):
        self.legs = list(legs)
        if not self.legs:
            raise InputError("a mechanism needs at least one leg")
        for i, leg in enumerate(self.legs):
            if not isinstance(leg, Leg):
                raise InputError(f"legs[{i}] is a {type(leg).__name__}, not a pkm_pin.Leg")
        names = [leg.name for leg in self.legs]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise InputError(f"leg names must be distinct; repeated: {dup}")
        anchors = [pin.SE3.Identity()] * len(self.legs) if anchors is None else list(anchors)
        if len(anchors) != len(self.legs):
            raise InputError(f"{len(anchors)} anchors given for {len(self.legs)} legs")
        for a in anchors:
            if not isinstance(a, pin.SE3):
                raise InputError("every anchor must be a pinocchio.SE3")
        self.anchors = anchors
        self.name = name
        self.description = description
        if not isinstance(length_unit, str) or not length_unit.strip():
            raise InputError(f"length_unit must be a unit name such as 'm' or 'mm', got "
                             f"{length_unit!r}")
        self.length_unit = length_unit
        self.home = as_pose(home) if home is not None else pin.SE3.Identity()
        if home_q is not None:
            if len(home_q) != len(self.legs):
                raise InputError(f"home_q has {len(home_q)} entries for {len(self.legs)} legs")
            home_q = [None if q is None else leg.check_q(q, "home_q")
                      for leg, q in zip(self.legs, home_q)]
        self.home_q = home_q
        #: The closure model this mechanism was detected in (:meth:`from_closure_model`:
        #: an Extended URDF, an MJCF file), and its structure; ``None`` for legs given
        #: directly (TOML).
        self.source_model = None
        self.structure = None

    @classmethod
    def from_model(cls, model, *, output: str | None = None, point: bool | None = None,
                   backend: str = "general", q=None, description: str = "") -> Mechanism:
        """The mechanism of any closure model (:class:`~pkm_pin.model.ClosureModel`).

        Args:
            output, point: Another output frame, or the output's origin as a point
                (:class:`~pkm_pin.linkage.Linkage`'s arguments).
            backend: ``"general"`` (the general elimination answers; a platform structure
                detected in the model serves the per-leg capabilities) or ``"legs"``
                (:meth:`from_closure_model`: the per-leg engine answers; the model must
                hold a base–legs–platform machine).
            q: For ``backend="legs"``, an assembled configuration of the tree.
            description: One line saying what it is.
        """
        if backend not in BACKENDS:
            raise InputError(f"backend={backend!r}: write one of "
                             f"{', '.join(map(repr, BACKENDS))}")
        if backend == "legs":
            link = Linkage(model, output, point)
            return cls.from_closure_model(link.model, q, description=description)
        return cls.of_linkage(Linkage(model, output, point), description=description)

    @classmethod
    def of_linkage(cls, link: Linkage, *, description: str = "") -> Mechanism:
        """The mechanism read by the general backend ``link`` (what it has computed,
        such as its home assembly, kept)."""
        if not isinstance(link, Linkage):
            raise InputError(f"of_linkage() takes a pkm_pin.linkage.Linkage, got "
                             f"{type(link).__name__}")
        mech = _ReadByGeneral.__new__(_ReadByGeneral)
        mech.description = description
        mech.__dict__["general"] = link.with_legs(mech._legs_at)
        return mech

    def _legs_at(self, q: np.ndarray) -> Mechanism:
        """The per-leg reading of the general backend's model at its configuration
        ``q`` (:attr:`Linkage.legs_mechanism`)."""
        return Mechanism.from_closure_model(self.general.model, q,
                                            description=self.description)

    def _itself(self, q: np.ndarray) -> Mechanism:
        """The per-leg reading of a per-leg mechanism: itself."""
        return self

    @cached_property
    def general(self) -> Linkage:
        """The general elimination of this mechanism (a
        :class:`~pkm_pin.linkage.Linkage` of :attr:`model`, whose reference
        configuration is home: its ``home_assembly`` is this mechanism's; cached): what
        answers mobility, idle motions, point outputs, any output frame and the
        transmission over the tree on a per-leg mechanism, and everything on a
        mechanism read by the general backend."""
        model = dataclasses.replace(self.model, reference=self.tree_configuration())
        return Linkage(model, legs=self._itself)

    @classmethod
    def from_closure_model(cls, model, q=None, *, description: str = "") -> Mechanism:
        """The mechanism of a closure model in which a base–legs–platform structure is
        detected (:func:`pkm_pin.model.structure.detect_platform`): one
        :class:`~pkm_pin.leg.Leg` per chain from the base to the platform, whatever tree
        the file wrote (TOML legs, an Extended URDF through one leg with point closures
        for the others, MJCF welds), so that the same machine gets the same analysis.

        Each closure leg ends as its closure says: a weld fixes its last body to the
        platform, a point closure becomes a spherical joint (three revolutes about x, y,
        z of a frame chosen so that their angles are zero at the home assembly, far from
        their gimbal lock), a revolute closure one revolute about the common z axis.
        The leg's first joint placement is its :attr:`~pkm_pin.leg.Leg.base`. The
        platform frame is the model's output frame; home is its placement at ``q``.

        Args:
            model: The :class:`~pkm_pin.model.ClosureModel`.
            q: An assembled configuration of the model's tree (default: the model's
                assembly from its reference, the file's intended working mode).
            description: One line saying what it is.

        Raises:
            InputError: no platform structure (the reason names the joint or closure
                that breaks it), or ``q`` does not close the loops.
        """
        from .model.structure import detect_platform

        structure, reason = detect_platform(model)
        if structure is None:
            raise InputError(f"{model.name or 'the model'}: not a base–legs–platform "
                             f"machine: {reason}")
        q = _assembled(model, q)
        data = model.tree.createData()
        pin.framesForwardKinematics(model.tree, data, q)
        home = data.oMf[model.tree.getFrameId(model.output)].copy()
        built = [_structure_leg(model, leg, q, data, home) for leg in structure.legs]
        legs, anchors, home_q = (list(x) for x in zip(*built))
        mech = cls(legs, anchors, name=model.name or "mechanism", home=home, home_q=home_q,
                   description=description)
        mech.source_model, mech.structure = model, structure
        return mech

    def source_configuration(self, assembly: Assembly | None = None) -> np.ndarray:
        """The configuration of :attr:`source_model`'s tree at ``assembly`` (default:
        home): each leg's joints from the leg's configuration, the platform's free flyer
        (if any) from the pose. Only for a mechanism made by
        :meth:`from_closure_model`."""
        if self.source_model is None:
            raise InputError(f"{self.name!r} was not detected in a closure model: its "
                             "configuration is per leg (Assembly.leg_q)")
        assembly = self.home_assembly if assembly is None else assembly
        tree, structure = self.source_model.tree, self.structure
        q = np.array(self.source_model.reference, dtype=float)
        for leg, q_leg in zip(structure.legs, assembly.leg_q):
            k = 0
            for j in leg.joints:
                nq = tree.joints[j].nq
                q[tree.joints[j].idx_q:tree.joints[j].idx_q + nq] = q_leg[k:k + nq]
                k += nq
        if structure.free_flyer:
            j = structure.platform_joint
            output = tree.frames[tree.getFrameId(self.source_model.output)].placement
            M = tree.jointPlacements[j].actInv(assembly.pose * output.inverse())
            q[tree.joints[j].idx_q:tree.joints[j].idx_q + 7] = pin.SE3ToXYZQUAT(M)
        return q

    def __getstate__(self) -> dict:
        """Pickle without the cached home analysis, closure model and general reading
        (recomputed on demand; the closure model's Pinocchio tree may hold mimic joints,
        which Pinocchio 4.1 does not unpickle soundly: see :meth:`Leg.__getstate__`)."""
        return {k: v for k, v in self.__dict__.items()
                if k not in ("home_analysis", "closure_model", "tree_pass", "general")}

    def __repr__(self) -> str:
        return f"Mechanism({self.name!r}, legs={[leg.name for leg in self.legs]})"

    # -------------------------------------------- the general backend's answers
    def _tree_q(self, q):
        """The tree configuration of ``q``: an :class:`Assembly` of this mechanism
        (:meth:`tree_configuration`), a tree configuration as it is, ``None``: home."""
        if q is None:
            return self.general.home_assembly.q
        return self.tree_configuration(q) if isinstance(q, Assembly) else q

    @property
    def legs_mechanism(self) -> Mechanism:
        """The per-leg reading of this mechanism: itself (read by the general backend,
        the machine detected in its model, or the reason there is none)."""
        return self

    @property
    def platform_structure(self) -> tuple:
        """``(structure, reason)``: the base–legs–platform machine detected in
        :attr:`model` (:func:`pkm_pin.model.structure.detect_platform`)."""
        return self.general.platform_structure

    def mobility(self, q=None, **options):
        """The mobility at ``q`` (an :class:`Assembly`, a tree configuration; default
        home) over the whole tree, its ranks compared with nearby configurations on
        the closure manifold (:meth:`pkm_pin.linkage.Linkage.mobility`)."""
        return self.general.mobility(self._tree_q(q), **options)

    def transmission(self, q=None, **options):
        """The transmission indices over the tree at ``q`` (an :class:`Assembly`, a tree
        configuration; default home), each actuator's side of its loops its "leg"
        (:meth:`pkm_pin.linkage.Linkage.transmission`)."""
        return self.general.transmission(self._tree_q(q), **options)

    def submechanisms(self, q=None) -> list:
        """The independent sub-mechanisms at ``q`` (:meth:`pkm_pin.linkage.Linkage.
        submechanisms`): ``[self]`` for one mechanism (a platform machine is one: its
        legs share the platform)."""
        if self.backend == "legs":
            return [self]
        subs = self.general.submechanisms(self._tree_q(q))
        return [self if sub is self.general else sub for sub in subs]

    def tree_sensitivity(self, q=None, parameters=None):
        """Sensitivity of the output to any parameter of the model's tree
        (:meth:`pkm_pin.linkage.Linkage.tree_sensitivity`) at ``q`` (default home)."""
        return self.general.tree_sensitivity(self._tree_q(q), parameters)

    def reached(self, error: LoopClosureError):
        """Where an assembly that failed stopped (:meth:`pkm_pin.linkage.Linkage.reached`)."""
        return self.general.reached(error)

    def legs_assembly(self, q=None) -> Assembly:
        """The :class:`Assembly` at the configuration ``q`` of :attr:`model`'s tree
        (:attr:`Assembly.q`; default home): the pose of the output there, the legs
        solved from ``q``'s values (:meth:`assemble` with them as the guess, so the
        result is checked to close). A machine detected in a file reads its legs'
        joints off the file's tree (:meth:`pkm_pin.linkage.Linkage.legs_assembly`); a
        TOML machine's tree is its legs, then the platform's free flyer."""
        if q is None:
            return self.home_assembly
        q = self.model.check_q(np.asarray(self._tree_q(q), dtype=float))
        if self.structure is not None:
            return self.general.legs_assembly(q)
        ends = np.cumsum([0] + [leg.nq for leg in self.legs])
        pose = pin.XYZQUATToSE3(q[ends[-1]:ends[-1] + 7])
        return self.assemble(pose, guess=[q[a:b] for a, b in zip(ends[:-1], ends[1:])])

    # ------------------------------------------------------------------ counts
    @property
    def actuated_names(self) -> list[str]:
        """Actuated joints in the order of the actuated coordinates: as ``"leg/joint"``
        for legs given directly (TOML: two legs may name a joint alike), as the file
        names them for a machine detected in a file (:meth:`from_closure_model`: a
        tree's joint names are distinct)."""
        if self.source_model is not None:
            return [a for leg in self.legs for a in leg.actuated]
        return [f"{leg.name}/{a}" for leg in self.legs for a in leg.actuated]

    @property
    def n_actuated(self) -> int:
        """Number of actuated coordinates."""
        return sum(len(leg.actuated) for leg in self.legs)

    @cached_property
    def characteristic_length(self) -> float:
        """Unit of length of the relative tolerances [m]: mean of the legs' lengths
        (:attr:`Leg.offset_length`) over the legs that have one (a leg whose joints and
        tip all sit at one point brings no length); 1.0 when none has."""
        lengths = [leg.offset_length for leg in self.legs if leg.offset_length > 0]
        return float(np.mean(lengths)) if lengths else 1.0

    @cached_property
    def actuated_scales(self) -> np.ndarray:
        """Unit of each actuated coordinate (cached; do not modify it in place): the
        :attr:`characteristic_length` [m] for a prismatic joint, 1 rad for a revolute
        one. Actuated errors divided by it are the dimensionless errors the position
        solvers compare with their tolerances."""
        out = []
        L = self.characteristic_length
        for leg in self.legs:
            prismatic = {leg.model.joints[j].idx_q for j in leg._prismatic_joints}
            out += [L if int(iq) in prismatic else 1.0 for iq in np.atleast_1d(leg.actuated_q)]
        return np.array(out, dtype=float)

    @cached_property
    def kernel(self):
        """The mechanism's compiled kinematics (:class:`pkm_pin.kernels.MechanismKernel`,
        read-only arrays for the compiled solvers; cached and pickled with the
        mechanism), or ``None`` when a leg has a joint the kernels do not represent."""
        from .kernels import mechanism_kernel

        return mechanism_kernel(self, self.actuated_scales.copy())

    @cached_property
    def leg_frames(self) -> LegFrames:
        """The legs' base and anchor placements, velocity offsets and lengths as arrays
        (:class:`pkm_pin.twists.LegFrames`; cached)."""
        return leg_frames(self)

    @cached_property
    def closure_model(self):
        """The description as one tree plus closures (:class:`pkm_pin.model.ClosureModel`,
        :func:`pkm_pin.model.from_mechanism`: the legs under the universe at their bases,
        the platform a free flyer, each tip welded to it; cached)."""
        from .model import from_mechanism

        return from_mechanism(self)

    # The names every mechanism answers (a Linkage has the same): the closure model, its
    # actuated joints and output frame.
    @property
    def model(self):
        """The closure model (:attr:`closure_model`: the file's own when the mechanism
        was detected in one, :attr:`source_model`)."""
        return self.source_model if self.source_model is not None else self.closure_model

    @property
    def actuated(self) -> tuple:
        """Names of the actuated joints, in the order of the actuated coordinates
        (:attr:`actuated_names`)."""
        return tuple(self.actuated_names)

    @property
    def output(self) -> str:
        """The output frame: the platform frame of :attr:`model`."""
        return self.model.output

    @cached_property
    def tree_pass(self) -> TreePass | None:
        """Pinocchio's pass over every leg in one call (:class:`pkm_pin.twists.TreePass`,
        on :attr:`closure_model`'s tree), or ``None`` when a leg has mimic joints (then
        each leg is evaluated on its own); cached."""
        return None if has_mimic(self) else TreePass(self)

    @cached_property
    def engine_layout(self) -> Layout:
        """The analysis engine's :class:`~pkm_pin.engine.Layout` of this mechanism at the
        default rank tolerance (cached)."""
        return layout_of(self)

    @cached_property
    def sweep_layout(self) -> Layout:
        """:attr:`engine_layout` with the reference of the carried determinant: the home
        pose's platform twists, homogenised about the home centre (what
        :meth:`sweep` analyses with at the default rank tolerance; cached)."""
        home = self.home_analysis
        reference = homogenise(home._about_centre(home.platform_twists),
                               self.characteristic_length)
        return self.engine_layout._replace(reference=reference)

    @property
    def grubler(self) -> int:
        """Grübler–Kutzbach count ``6 (1 − legs) + Σ leg nv`` (1-DOF joints, mimic pairs
        counted once). Wrong for overconstrained mechanisms: compare with
        :attr:`Analysis.dof`."""
        return 6 * (1 - len(self.legs)) + sum(leg.nv for leg in self.legs)

    # ---------------------------------------------------------------- assembly
    @cached_property
    def home_assembly(self) -> Assembly:
        """The assembly at :attr:`home` (working mode from ``home_q`` when given)."""
        return self.assemble(self.home, guess=self.home_q)

    @cached_property
    def home_analysis(self) -> Analysis:
        """The :class:`~pkm_pin.analysis.Analysis` of the home assembly (the reference
        for constraint singularities: the home pose is taken as a generic pose)."""
        return self.analyze(self.home_assembly)

    def assemble(self, pose=None, guess=None, *, tol: float = CLOSURE_TOL,
                 restarts: int = 24, project: bool = True) -> Assembly:
        """Solve every leg so that its tip coincides with ``pose * anchor``.

        Args:
            pose: Platform pose (``pin.SE3``, 4×4 matrix or x, y, z, roll, pitch, yaw), or
                a partial pose: a mapping of some of x, y, z, roll, pitch, yaw to values
                (completed first, :meth:`complete_pose`; ``info["given"]``,
                ``info["held"]``); default :attr:`home` (every mechanism assembles
                without an argument, as a general-backend one from its reference); or,
                as a general-backend mechanism takes it, a configuration of
                :attr:`model`'s tree that need not close: the loops are closed nearest
                it (:meth:`pkm_pin.linkage.Linkage.assemble`) and the result read per
                leg (:meth:`legs_assembly`).
            guess: An :class:`Assembly` or a list of leg configurations to warm-start
                from (default: the home assembly), which keeps the legs on its branch.
            tol: Relative closure tolerance of each leg.
            restarts: Restarts of a leg solver that stalls (see :meth:`Leg.solve`).
            project: A full pose that some leg cannot reach is projected onto the
                mechanism's motion manifold when the nearest pose differs from it by at
                most :data:`~pkm_pin.tolerances.POSE_PROJECTION_TOL` (a lower-mobility
                mechanism's pose at printed precision; ``info["projection"]``, the
                difference, and ``info["projected_from"]``).

        A leg that stalls at its type I singularity or at a joint limit (a pose on the
        workspace boundary, where Newton converges only like a square root) with a
        residual below :data:`~pkm_pin.tolerances.TYPE_I_CLOSURE_TOL` is accepted:
        ``info["boundary"]`` names it and ``residual`` is the closure reached.

        Raises:
            AssemblyError: a leg cannot reach the pose within its joint limits (and the
                pose is not within the projection tolerance of the motion manifold).
            DependentCoordinates, ForwardKinematicsError: a partial pose that is not
                one of the mechanism's independent coordinates, or cannot be completed.
        """
        pose = self.home if pose is None else pose
        tol = as_fraction(tol, "tol")
        if self._is_tree_configuration(pose):
            return self.legs_assembly(self.general.assemble(pose, tol=tol).q)
        if isinstance(restarts, bool) or not isinstance(restarts, (int, np.integer)) \
                or restarts < 0:
            raise InputError(f"restarts must be a non-negative integer, got {restarts!r}")
        if not isinstance(pose, pin.SE3) and isinstance(pose, Mapping):
            done = position.complete(self, pose, guess, tol=tol)
            asm = self._assemble_pose(done.pose, done.leg_q, tol, restarts)
            asm.info.update(done.info)
            return asm
        pose = as_pose(pose)
        try:
            return self._assemble_pose(pose, self.leg_starts(guess), tol, restarts)
        except AssemblyError as e:
            if not project:
                raise
            failure = e
        try:
            near = position.project_pose(self, pose, guess, closure_tol=tol)
        except position.OffMotionManifold as e:
            raise e from failure
        except AssemblyError:
            raise failure from None
        asm = self._assemble_pose(near.pose, near.leg_q, tol, 0)
        asm.info.update(near.info)
        return asm

    def _assemble_pose(self, pose: pin.SE3, starts: list, tol: float,
                       restarts: int) -> Assembly:
        """:meth:`assemble` of a full pose from the leg configurations ``starts``."""
        kernel = self.kernel
        if kernel is not None and all(q is not None for q in starts) \
                and prefer_compiled(solve_system):
            return self._assemble_compiled(kernel, pose, starts, tol, restarts)
        leg_q, worst, boundary = [], 0.0, []
        for i, q0 in enumerate(starts):
            q, residual = self._solve_leg(i, pose, q0, tol, restarts, boundary)
            leg_q.append(q)
            worst = max(worst, residual)
        asm = Assembly(self, pose, leg_q, worst)
        if boundary:
            asm.info["boundary"] = boundary
        return asm

    def _solve_leg(self, i: int, pose: pin.SE3, q0, tol: float, restarts: int,
                   boundary: list) -> tuple[np.ndarray, float]:
        """Leg ``i`` at ``pose * anchor`` (:meth:`Leg.solve` with its restarts); a leg
        stalled on the workspace boundary (:func:`stalled_at_boundary`) is accepted and
        named in ``boundary``. Returns its configuration and residual."""
        leg = self.legs[i]
        sol = leg.solve(pose * self.anchors[i], q0, tol=tol, restarts=restarts)
        if sol.converged:
            return sol.q, sol.residual
        if stalled_at_boundary(leg, sol.q, sol.residual):
            boundary.append(leg.name)
            return sol.q, sol.residual
        raise AssemblyError(leg.name, sol.residual)

    def _assemble_compiled(self, kernel, pose: pin.SE3, starts: list, tol: float,
                           restarts: int) -> Assembly:
        """:meth:`assemble` from warm starts: the closure solver with mask LEGS in one
        compiled call (:func:`pkm_pin.solve.solve_kernel`; the starts projected onto the
        limits), then one Pinocchio pass per leg that verifies each closure and gives the
        joint twists the analysis needs; a leg it does not confirm is solved again by
        :meth:`Leg.solve` (with its restarts)."""
        Q = np.concatenate(starts)
        M = pose.homogeneous
        solve_kernel(kernel, LEGS, M, Q, tol=tol, max_iter=50)
        leg_q = [Q[s] for s in kernel.slices]
        J, errors, worst = verified_twists(self, leg_q, M, flat=Q)
        boundary = []
        if not worst <= tol:  # a leg Pinocchio does not confirm: Leg.solve, restarts
            for i in np.flatnonzero(~(errors <= tol)):
                leg_q[i], _ = self._solve_leg(int(i), pose, leg_q[i], tol, restarts, boundary)
            J, errors, worst = verified_twists(self, leg_q, M)
        asm = Assembly(self, pose, leg_q, worst, joint_twists=J)
        if boundary:
            asm.info["boundary"] = boundary
        return asm

    def complete_pose(self, guess=None, **coords) -> pin.SE3:
        """The full pose on the motion manifold at a partial pose: ``coords`` some of x,
        y, z [m], roll, pitch, yaw [rad] that are independent coordinates of the
        mechanism (a 3-RPS: ``z=…, roll=…, pitch=…``), the others solved for from
        ``guess`` (default home; its branch is kept).

        See :func:`pkm_pin.position.complete_pose`.
        """
        return position.complete_pose(self, guess, **coords)

    def leg_starts(self, guess=None) -> list:
        """The leg configurations an assembly warm-starts from (one per leg; ``None``:
        the leg's neutral configuration).

        ``guess``: an :class:`Assembly`, a list of leg configurations, or ``None``: the
        home assembly once it has been computed, else ``home_q`` (the home assembly is
        itself solved from ``home_q``).
        """
        if guess is None:
            if "home_assembly" in self.__dict__:
                return list(self.home_assembly.leg_q)
            return list(self.home_q) if self.home_q is not None else [None] * len(self.legs)
        if isinstance(guess, Assembly):
            return list(self._per_leg(guess).leg_q)
        guess = list(guess)
        if len(guess) != len(self.legs):
            raise InputError(f"guess has {len(guess)} leg configurations for {len(self.legs)} legs")
        return [None if q is None else leg.check_q(q, "guess") for leg, q in zip(self.legs, guess)]

    def check_actuated(self, q_actuated, name: str = "q_actuated") -> np.ndarray:
        """``q_actuated`` as a finite array of the right length, or a specific error."""
        return as_vector(q_actuated, self.n_actuated, name, ", ".join(self.actuated_names))

    # ----------------------------------------------------------------- analysis
    def assembly_at(self, pose_or_assembly=None) -> Assembly:
        """The home assembly (``None``), an :class:`Assembly` as it is, the assembly at
        a configuration of the whole tree (a vector of ``model.tree.nq`` numbers, as
        :attr:`Assembly.q` and a general linkage's configurations are; read per leg,
        :meth:`legs_assembly`), or the assembly at a pose (:meth:`assemble` from home; a
        6-vector is a pose ``(x, y, z, roll, pitch, yaw)``)."""
        if pose_or_assembly is None:
            return self.home_assembly
        if isinstance(pose_or_assembly, Assembly):
            return self._per_leg(pose_or_assembly)
        if self._is_tree_configuration(pose_or_assembly):
            return self.legs_assembly(pose_or_assembly)
        return self.assemble(pose_or_assembly)

    def _per_leg(self, assembly: Assembly) -> Assembly:
        """``assembly`` with its per-leg view: as it is when it has one, else (one the
        general backend made, of this mechanism's tree) read per leg
        (:meth:`legs_assembly` at its :attr:`Assembly.q`)."""
        return assembly if assembly.leg_q is not None else self.legs_assembly(assembly.q)

    def _is_tree_configuration(self, x) -> bool:
        """Whether ``x`` is a configuration of :attr:`model`'s tree (a 1-D vector of its
        ``nq`` numbers, ``nq`` ≠ 6: six numbers are a pose)."""
        if isinstance(x, pin.SE3) or self.model.tree.nq == 6:
            return False
        shape = np.shape(x)
        return len(shape) == 1 and shape[0] == self.model.tree.nq

    def analyze(self, pose_or_assembly=None, **options) -> Analysis:
        """Screw analysis (:class:`~pkm_pin.analysis.Analysis`) at a pose or assembly
        (default: home)."""
        return Analysis(self.assembly_at(pose_or_assembly), **options)

    # ------------------------------------------------------- position problems
    def forward_kinematics(self, q_actuated, guess=None, *, steps: int | None = None,
                           tol: float = CLOSURE_TOL, inertia_tol: float = INERTIA_TOL,
                           max_newton: int = 50, max_inertia: int = 200,
                           method: str = "auto", starts: int | None = None,
                           seed: int = 0) -> Assembly:
        """Platform pose (an :class:`Assembly`) for the actuated coordinates, by
        continuation from ``guess`` (default: home; an :class:`Assembly`, a pose or a
        configuration of :attr:`model`'s tree).

        See :func:`pkm_pin.position.forward_kinematics`.
        """
        return position.forward_kinematics(
            self, q_actuated, guess, steps=steps, tol=tol, inertia_tol=inertia_tol,
            max_newton=max_newton, max_inertia=max_inertia, method=method, starts=starts,
            seed=seed)

    def forward_kinematics_all(self, q_actuated, *, starts: int = 32, seed: int = 0,
                               tol: float = CLOSURE_TOL, max_iter: int = 100,
                               method: str = "auto") -> list[Assembly]:
        """Every assembly mode found for ``q_actuated``: deduplicated by pose, each valid.

        See :func:`pkm_pin.position.forward_kinematics_all`.
        """
        return position.forward_kinematics_all(self, q_actuated, starts=starts, seed=seed,
                                               tol=tol, max_iter=max_iter, method=method)

    def inverse_kinematics(self, pose, guess=None) -> Assembly:
        """The :class:`Assembly` at ``pose`` (legs on the working mode of ``guess``,
        default home); its ``q_actuated`` are the actuated coordinates.

        See :func:`pkm_pin.position.inverse_kinematics`.
        """
        return position.inverse_kinematics(self, pose, guess)

    def inverse_kinematics_all(self, pose, *, starts: int = 16, seed: int = 0,
                               max_modes: int = 4096) -> list[Assembly]:
        """Every working mode at ``pose``: the distinct actuated-coordinate vectors.

        See :func:`pkm_pin.position.inverse_kinematics_all`.
        """
        return position.inverse_kinematics_all(self, pose, starts=starts, seed=seed,
                                               max_modes=max_modes)

    # ------------------------------------------------------------------ studies
    def sensitivity(self, assembly=None, parameters=None) -> _sensitivity.Sensitivity:
        """Platform pose error per unit parameter error; ``assembly`` defaults to home.

        See :func:`pkm_pin.sensitivity.sensitivity`.
        """
        return _sensitivity.sensitivity(self, assembly, parameters)

    def calibrate(self, samples, parameters, **options):
        """Identify the errors of ``parameters`` from measured platform poses or
        positions after known actuations: :func:`pkm_pin.calibration.calibrate`
        (``samples``: pairs ``(q_actuated, measured)``)."""
        from .calibration import calibrate

        return calibrate(self, samples, parameters, **options)

    def workspace(self, coords=None, **options):
        """The reachable, singularity-free and good-transmission workspaces over some of
        the pose coordinates (default the independent ones), with volumes and inscribed
        shapes (a :class:`~pkm_pin.workspace.Workspace`).

        See :func:`pkm_pin.workspace.workspace`.
        """
        from .workspace import workspace

        return workspace(self, coords, **options)

    def inverse_dynamics(self, q, v, a, *, gravity=(0, 0, -9.81), wrench=None):
        """Actuated efforts and closure forces of the motion ``(q, v, a)`` of
        :attr:`source_model`'s tree for a mechanism detected in a file, else of
        :attr:`closure_model`'s (:func:`pkm_pin.dynamics.inverse_dynamics`; efforts in
        that model's ``actuated`` order)."""
        model = self.closure_model if self.source_model is None else self.source_model
        return _dynamics.inverse_dynamics(model, q, v, a, gravity=gravity, wrench=wrench)

    def simulate(self, q0=None, v0=None, duration: float = 1.0, dt: float = 1e-3,
                 **options):
        """Forward dynamics of the model :meth:`inverse_dynamics` uses, from ``(q0, v0)``
        (default: the home configuration, at rest): :func:`pkm_pin.simulation.simulate`
        (``options``: ``efforts``, ``controller``, ``gravity``, ``baumgarte``, ``method``,
        ``integrator``)."""
        from . import simulation
        q0 = self.tree_configuration() if q0 is None else q0
        return simulation.simulate(self.model, q0, v0, duration, dt, **options)

    def dynamic_indices(self, q=None):
        """Actuator-space inertia, its eigenvalues and condition, the apparent inertia at
        the output, at ``q`` (a configuration of the model :meth:`inverse_dynamics` uses;
        default home): :func:`pkm_pin.dynamic_indices.dynamic_indices`."""
        from . import dynamic_indices as _indices
        return _indices.dynamic_indices(self.model,
                                        self.tree_configuration() if q is None
                                        else q)

    def gravity_map(self, poses, *, gravity=(0, 0, -9.81), wrench=None,
                    condition: bool = False):
        """Gravity efforts over ``poses`` (a sequence of ``pin.SE3``), each assembled
        warm-started from the last one assembled (a pose that does not assemble: a nan
        row): :func:`pkm_pin.dynamic_indices.gravity_efforts`."""
        from . import dynamic_indices as _indices
        model = self.model
        Q, guess = np.full((len(poses), model.nq), np.nan), self.home_assembly
        for i, pose in enumerate(poses):
            try:
                guess = self.assemble(pose, guess)
            except PkmError:
                continue
            Q[i] = self.tree_configuration(guess)
        return _indices.gravity_efforts(model, Q, gravity=gravity, wrench=wrench,
                                        condition=condition)

    def tree_configuration(self, assembly: Assembly | None = None) -> np.ndarray:
        """The configuration of :attr:`model`'s tree at ``assembly`` (default home): the
        file's tree (:meth:`source_configuration`) for a mechanism detected in one,
        else the legs-and-platform tree of :attr:`closure_model`
        (:func:`pkm_pin.model.configuration`). Every mechanism answers it (a
        :class:`~pkm_pin.linkage.Linkage` too), so the dynamics and studies that work on
        the tree ask no question about the kind of mechanism."""
        assembly = self.home_assembly if assembly is None else assembly
        if assembly.leg_q is None:  # the general backend's: the tree's q is what it holds
            return assembly.q
        if self.source_model is not None:
            return self.source_configuration(assembly)
        from .model import configuration as configuration_of
        return configuration_of(self, assembly)

    def sweep(self, poses, *, executor: Executor | None = None, chunk_size: int = 2000,
              progress: bool = False, rtol: float | None = None,
              singular_tol: float = CLOSENESS_SINGULAR_TOL,
              transmission: bool = False, checkpoint=None) -> _sweep.SweepResult:
        """Assemble and analyse the mechanism at every pose.

        ``poses``: full poses (a sequence of ``pin.SE3`` or an (N, 6) array), or partial
        poses (:meth:`complete_pose`): a sequence of mappings ``{"z": …, "roll": …,
        "pitch": …}``, or one mapping of coordinate names to equal-length sequences (or
        scalars, repeated), e.g. ``{"z": zs, "roll": rolls, "pitch": 0.0}``. Partial poses
        are completed in the order given, each warm-started from the last one completed
        (from home for the first), the coordinates' plan (which are held when fewer than
        the DOF are given, :func:`pkm_pin.position.coordinate_plan`) made at the first
        completion and kept: order them along a path or a
        snake for a continuous branch. A partial pose that cannot be completed is a
        failure of the result (its pose row holds the given coordinates, nan elsewhere).

        See :func:`pkm_pin.sweep.sweep` (``checkpoint``: the sweep of the completed
        poses is checkpointed; their completion is redone on a resume).
        """
        options = dict(executor=executor, chunk_size=chunk_size, progress=progress,
                       rtol=rtol, singular_tol=singular_tol, transmission=transmission,
                       checkpoint=checkpoint)
        partial = _partial_poses(poses)
        if partial is None:
            return _sweep.sweep(self, poses, **options)
        full, failures, previous, plan = np.full((len(partial), 6), np.nan), [], None, None
        for i, coords in enumerate(partial):
            try:  # the coordinates' plan made at the first completion, then kept
                done = position.complete(self, coords, previous, plan=plan)
            except PkmError as e:
                failures.append((i, f"not completed: {e}"))
                for name, value in position.partial_pose(coords).items():
                    full[i, POSE_COORDINATES.index(name)] = value
                continue
            full[i] = position.pose_coordinates(done.pose)
            for name, value in done.info["given"].items():  # exactly as given
                full[i, POSE_COORDINATES.index(name)] = value
            previous, plan = done, done.info["plan"]
        done_idx = np.flatnonzero(np.isfinite(full).all(axis=1))
        if not len(done_idx):
            return _failed_sweep(self, full, failures, singular_tol)
        return _scatter(_sweep.sweep(self, full[done_idx], **options), full, done_idx,
                        failures)




def _partial_poses(poses) -> list | None:
    """The partial poses of :meth:`Mechanism.sweep` as a list of mappings, or ``None``
    when ``poses`` are full poses."""
    if isinstance(poses, Mapping):
        sizes = {len(v) for v in poses.values() if np.ndim(v) == 1}
        if len(sizes) > 1:
            raise InputError(f"the coordinates of partial poses must have equal lengths, "
                             f"got {sorted(sizes)}")
        n = sizes.pop() if sizes else 1
        for k, v in poses.items():
            if np.ndim(v) > 1:
                raise InputError(f"partial poses: {k} must be a number or a 1-D sequence")
        columns = {k: (np.asarray(v, dtype=float) if np.ndim(v) == 1 else np.full(n, v))
                   for k, v in poses.items()}
        return [{k: float(c[i]) for k, c in columns.items()} for i in range(n)]
    if isinstance(poses, (list, tuple)) and poses and all(isinstance(p, Mapping)
                                                          for p in poses):
        return list(poses)
    return None


def _scatter(result: _sweep.SweepResult, full: np.ndarray, idx: np.ndarray,
             failures: list) -> _sweep.SweepResult:
    """A sweep result over every pose from the result over the rows ``idx``: each
    per-pose array scattered (nan, −1, "" or False elsewhere), failures merged."""
    rows, out = len(result.poses), {}
    for f in dataclasses.fields(result):
        a = getattr(result, f.name)
        if f.name == "poses":
            out[f.name] = full
        elif isinstance(a, np.ndarray) and a.ndim >= 1 and a.shape[0] == rows:
            b = np.empty((len(full),) + a.shape[1:], dtype=a.dtype)
            b[...] = _fill_value(a.dtype)
            b[idx] = a
            out[f.name] = b
        elif f.name == "failures":
            out[f.name] = sorted(failures + [(int(idx[i]), r) for i, r in a])
        else:
            out[f.name] = a
    return type(result)(**out)


def _fill_value(dtype):
    """What a sweep array holds where a pose did not assemble."""
    if dtype.kind == "b":
        return False
    if dtype.kind in "iu":
        return -1
    if dtype.kind in "US":
        return ""
    return np.nan


def _failed_sweep(mech, full: np.ndarray, failures: list, singular_tol: float
                  ) -> _sweep.SweepResult:
    """The sweep result of poses none of which was completed."""
    result = _sweep._gather(full, [], [], mech.n_actuated, singular_tol)
    return dataclasses.replace(result, failures=sorted(failures))


def stalled_at_boundary(leg: Leg, q: np.ndarray, residual: float) -> bool:
    """Whether a leg that stalled at ``q`` with the relative closure ``residual`` is on
    its workspace boundary and close enough to be accepted: ``residual ≤``
    :data:`~pkm_pin.tolerances.TYPE_I_CLOSURE_TOL` and either a joint at a finite limit
    (within :data:`~pkm_pin.tolerances.JOINT_LIMIT_SLACK`) or the leg at its type I
    singularity: its :meth:`~pkm_pin.serial.SerialChain.serial_singularity_index` (the
    smallest singular value of its homogenised Jacobian relative to the largest) at most
    ``TYPE_I_STALL_FACTOR · √residual`` (Newton's square-root convergence there)."""
    if not residual <= TYPE_I_CLOSURE_TOL:
        return False
    lo, up = leg._bounds
    finite = np.isfinite(lo) & np.isfinite(up)
    if np.any(finite & ((q <= lo + JOINT_LIMIT_SLACK) | (q >= up - JOINT_LIMIT_SLACK))):
        return True
    return bool(leg.serial_singularity_index(q) <= TYPE_I_STALL_FACTOR * np.sqrt(residual))


# ----------------------------------------------------- legs of a detected structure
#: Names of the revolutes that stand for a point closure's spherical joint.
_SPHERICAL = (("x", pin.JointModelRX), ("y", pin.JointModelRY), ("z", pin.JointModelRZ))


def _assembled(model, q) -> np.ndarray:
    """``q`` checked to close ``model``'s loops, or the model's assembly from its
    reference."""
    if q is None:
        sol, _ = solve_tree_starts(model, iter_tree_starts(model, None),
                                   nearest=model.reference)
        if not sol.converged:
            raise InputError(f"{model.name or 'the model'} does not assemble from its "
                             f"reference (closure residual {sol.residual:.3g}): give q")
        return np.array(sol.q)
    q = as_vector(q, model.nq, "q", "the tree's configuration vector")
    residual = float(np.abs(model.closure_residual(q)).max(initial=0.0))
    if residual > CLOSURE_TOL:
        raise InputError(f"q does not close the loops of {model.name!r} (largest "
                         f"dimensionless residual {residual:.3g} > {CLOSURE_TOL:g})")
    return q


def _structure_leg(model, leg, q: np.ndarray, data, home: pin.SE3):
    """``(Leg, anchor, home_q)`` of one :class:`~pkm_pin.model.structure.PlatformLeg`:
    the leg's joints copied from the tree (the first one's placement is the leg's base),
    the closure's joint(s) and a tip frame appended, written as URDF text
    (:func:`pkm_pin.model.chain_urdf.chain_urdf`) and read back as any leg, so that
    sensitivity and calibration name and perturb its parameters."""
    tree = model.tree
    chain, base = _chain_of(tree, leg)
    home_q = [q[tree.joints[j].idx_q:tree.joints[j].idx_q + tree.joints[j].nq]
              for j in leg.joints]
    anchor = home.actInv(data.oMf[tree.getFrameId(leg.platform_frame)]
                         * leg.platform_placement)
    if leg.kind == "tree":  # the tip at the platform joint's origin, as a TOML leg's
        output = chain.frames[chain.getFrameId(leg.frame, pin.FrameType.BODY)]
        tip = _unique(chain, f"{leg.name}_tip")
        chain.addBodyFrame(tip, output.parentJoint, pin.SE3.Identity(), output.parentFrame)
        anchor = output.placement.inverse()
    else:
        tip = _closure_tip(chain, leg, data, anchor, home, tree)
        home_q.append(np.zeros(chain.nq - sum(len(x) for x in home_q)))
    actuated = tuple(tree.names[j] for j in leg.joints if tree.names[j] in model.actuated)
    built = Leg.from_urdf(chain_urdf(chain, tip, leg.name), tip, actuated, base, leg.name)
    return (dataclasses.replace(built, source=f"{model.name or 'model'}: leg {leg.name}"),
            anchor, np.concatenate(home_q) if home_q else np.zeros(0))


def _chain_of(tree: pin.Model, leg) -> tuple[pin.Model, pin.SE3]:
    """The Pinocchio model of the leg's joints (same joint models, placements, limits
    and inertias as in ``tree``; the first joint at the origin) with the leg-side frame
    of its closure, and the leg's base (its first joint's placement)."""
    chain = pin.Model()
    chain.name = leg.name
    base, parent, previous = pin.SE3.Identity(), 0, 0
    new = {0: 0}
    for j in leg.joints:
        at = tree.jointPlacements[j]
        if parent == 0:
            base, at = at.copy(), pin.SE3.Identity()
        iq, nq, iv, nv = tree.joints[j].idx_q, tree.joints[j].nq, tree.joints[j].idx_v, \
            tree.joints[j].nv
        parent = chain.addJoint(parent, tree.joints[j], at, tree.names[j],
                                tree.effortLimit[iv:iv + nv], tree.velocityLimit[iv:iv + nv],
                                tree.lowerPositionLimit[iq:iq + nq],
                                tree.upperPositionLimit[iq:iq + nq])
        chain.appendBodyToJoint(parent, tree.inertias[j], pin.SE3.Identity())
        previous = chain.addJointFrame(parent, previous)
        new[j] = parent
    frame = tree.frames[tree.getFrameId(leg.frame)]
    at = frame.placement if frame.parentJoint else base.actInv(frame.placement)
    chain.addBodyFrame(leg.frame, new[frame.parentJoint], at, previous)
    return chain, base


def _closure_tip(chain: pin.Model, leg, data, anchor: pin.SE3, home: pin.SE3,
                 tree: pin.Model) -> str:
    """Append the joints a closure stands for (none for a weld, a revolute about z for a
    revolute closure, three revolutes for a point) at its leg-side constraint frame, and
    the tip frame; returns the tip frame's name. The joints' frame is turned so that the
    tip coincides with the platform's constraint frame at zero angles (home)."""
    # BODY: the leg's frame as added by _chain_of (an MJCF joint may share its name)
    frame = chain.frames[chain.getFrameId(leg.frame, pin.FrameType.BODY)]
    parent, at = frame.parentJoint, frame.placement * leg.placement
    C_leg = data.oMf[tree.getFrameId(leg.frame)] * leg.placement
    C_platform = home * anchor
    turn = pin.SE3(C_leg.rotation.T @ C_platform.rotation, np.zeros(3))
    axes = {"weld": (), "revolute": _SPHERICAL[2:], "point": _SPHERICAL}[leg.kind]
    previous = chain.getFrameId(leg.frame, pin.FrameType.BODY)
    joint_placement = at * turn if axes else at
    for axis, joint_model in axes:
        parent = chain.addJoint(parent, joint_model(), joint_placement,
                                _unique(chain, f"{leg.name}_{axis}"),
                                np.array([100.0]), np.array([10.0]),
                                np.array([-np.pi]), np.array([np.pi]))
        previous = chain.addJointFrame(parent, previous)
        joint_placement = pin.SE3.Identity()
    tip = _unique(chain, f"{leg.name}_tip")
    chain.addBodyFrame(tip, parent, joint_placement, previous)
    return tip


def _unique(model: pin.Model, name: str) -> str:
    """``name``, or ``name`` with a number appended, that no joint or frame of
    ``model`` has."""
    out, k = name, 1
    while model.existFrame(out) or model.existJointName(out):
        out, k = f"{name}_{k}", k + 1
    return out


class _ReadByGeneral(Mechanism):
    """A :class:`Mechanism` read by the general backend (:meth:`Mechanism.from_model`):
    the names the general elimination has (:class:`~pkm_pin.linkage.Linkage`) are its
    answers; those of the per-leg engine alone are the per-leg reading's
    (:attr:`~pkm_pin.linkage.Linkage.legs_mechanism`: the machine detected in the model,
    or an :class:`InputError` saying why there is none)."""

    backend = "general"
    submechanisms = Mechanism.submechanisms

    def __getattr__(self, name: str):
        # names of the general backend alone (idle motions, partial poses on linkages …)
        if name.startswith("__") or "general" not in self.__dict__:
            raise AttributeError(name)
        return getattr(self.__dict__["general"], name)

    def __dir__(self) -> list:
        return sorted(set(super().__dir__()) | {n for n in dir(self.general)
                                               if not n.startswith("_")})

    def __repr__(self) -> str:
        return f"Mechanism({self.name!r}, backend='general')"

    def __getstate__(self) -> dict:  # the general reading is all there is to keep
        return dict(self.__dict__)

    @property
    def name(self) -> str:
        return self.general.name

    @property
    def legs_mechanism(self) -> Mechanism:
        return self.general.legs_mechanism

    @property
    def structure(self):
        return self.general.platform_structure[0]

    @property
    def length_unit(self) -> str:
        return "m"

    @property
    def source_model(self):
        return self.general.model


def _forward(name: str, member, to: str):
    """``member`` of :class:`Mechanism` answered on a :class:`_ReadByGeneral` by the
    member of the same name of ``to`` (``"general"`` or ``"legs_mechanism"``)."""
    if isinstance(member, (property, cached_property)):
        return property(lambda self: getattr(getattr(self, to), name),
                        doc=(member.__doc__ if to == "legs_mechanism" else
                             getattr(Linkage, name).__doc__))

    def call(self, *args, **kwargs):
        return getattr(getattr(self, to), name)(*args, **kwargs)
    call.__name__ = call.__qualname__ = name
    call.__doc__ = member.__doc__ if to == "legs_mechanism" else getattr(Linkage, name).__doc__
    return call


for _name in ("legs", "anchors", "home", "home_q"):  # the per-leg description
    setattr(_ReadByGeneral, _name, property(
        lambda self, name=_name: getattr(self.legs_mechanism, name),
        doc=f"``{_name}`` of the machine detected in the model (:attr:`legs_mechanism`)."))
for _name, _member in list(vars(Mechanism).items()):
    if _name.startswith("_") or _name in vars(_ReadByGeneral) or _name == "general" \
            or isinstance(_member, (classmethod, staticmethod)):
        continue
    setattr(_ReadByGeneral, _name,
            _forward(_name, _member, "general" if hasattr(Linkage, _name) else "legs_mechanism"))
del _name, _member


__all__ = ["Assembly", "Mechanism", "as_pose", "placement"]
