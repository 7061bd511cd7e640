"""Command-line interface ``pkm-pin``: one entry point, one sub-command per task.

::

    pkm-pin list                                   shipped models, one line each
    pkm-pin analyze [MECHANISM] [--pose X Y Z R P Y | --at NAME=V... | --q Q...] [--json]
    pkm-pin check FILE                             validate a mechanism file and its URDFs
    pkm-pin fk MECHANISM Q... [--all]              actuated coordinates -> platform pose(s)
    pkm-pin ik MECHANISM [--pose X Y Z R P Y | --at NAME=V...] [--all]   pose -> actuated
    pkm-pin map MECHANISM --axes x z [--at NAME=V...] --range A B C D --n 100 --out PREFIX
    pkm-pin view MECHANISM [--pose ...] [--html FILE]   browser preview (meshcat)
    pkm-pin dynamics [MECHANISM] [--trajectory CSV] [--duration T] [--samples N]
                     [--simulate | --indices [--sub K]]
                     [--payload FX FY FZ MX MY MZ] [--json] [--out PREFIX]
                                                   actuator efforts along a motion

``MECHANISM`` is a mechanism file (``.toml``) or the name of a shipped model
(``pkm-pin list``). Poses are x, y, z [m] and URDF roll, pitch, yaw [rad]. A partial
pose ``--at z=0.8 roll=0.1 pitch=0`` gives some of them, independent coordinates of the
mechanism (a 3-RPS: z, roll, pitch; the agile eye: roll, pitch, yaw); the others
(parasitic motions) are solved for (:meth:`Mechanism.complete_pose`). ``map --axes``
varies any two independent coordinates (``--plane xy`` is ``--axes x y``), the others
given by ``--at`` or held at home.

General linkages (:class:`~pkm_pin.linkage.Linkage`: an Extended URDF ``.urdf`` with its
closures file, an MJCF ``.xml`` / ``.mjcf``, or a ``.toml`` whose legs meet at a pin) work
with every command; ``--output FRAME`` chooses the frame whose motion is analysed,
``--point`` / ``--body`` analyse its origin as a point or the frame as a body,
``--closures FILE`` names the closures file of a URDF (``--closures none``: its tree
without closures, every movable joint actuated: a serial arm). ``analyze``, ``check`` and
``view`` assemble from the file's reference configuration (``--q``: the actuated values,
forward kinematics first; ``--pose``: the output pose, inverse kinematics); ``map``
sweeps two actuated coordinates (``--actuated NAME NAME``, ``--range A B C D``) in a snake
so that each point is warm-started from its neighbour.

``map`` and ``workspace`` (platform mechanisms) keep their results in
``PREFIX.partial.npz`` while they run (:mod:`pkm_pin.checkpoint`): the first Ctrl-C or
SIGTERM stops after the current chunk, prints how many cells are done and the command that
continues (``--resume PREFIX``), and exits with 130 (SIGINT) or 143 (SIGTERM).

User mistakes print one line ``pkm-pin: error: …`` on stderr and exit with status 2; no
Python traceback. ``check`` exits with 1 when the file loads but has warnings.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path

import numpy as np

from .errors import InputError, PkmError, _clip
from .solve import POSE_COORDINATES
from .tolerances import CROSSCHECK_TOL

#: Pose coordinates in the order of ``--pose`` and of the sweep arrays.
POSE_NAMES = POSE_COORDINATES
#: Varied coordinates of each ``map --plane`` (``--axes`` takes any two).
PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def at_values(items, option: str = "--at") -> dict[str, float]:
    """A partial pose from ``NAME=VALUE`` items (NAME among x, y, z, roll, pitch, yaw)."""
    values = {}
    for item in items or ():
        name, _, text = item.partition("=")
        name = name.strip().lower()
        if name not in POSE_NAMES or not text:
            raise InputError(f"{option} takes NAME=VALUE with NAME in {', '.join(POSE_NAMES)}; "
                             f"got {item!r}")
        if name in values:
            raise InputError(f"{option}: {name} is given twice")
        values[name] = _number(text, f"{option} {name}")
    return values


def _platform_pose(args):
    """The pose of ``--pose`` (6 numbers), ``--at`` (a partial pose, as a dict) or None."""
    at = getattr(args, "at", None)
    if at is not None and args.pose is not None:
        raise InputError("give --pose (a full pose) or --at (a partial pose), not both")
    return at_values(at) if at is not None else args.pose
#: File suffixes read as general linkages (besides pinned ``.toml`` files).
LINKAGE_SUFFIXES = (".urdf", ".xml", ".mjcf")


# ----------------------------------------------------------------- mechanisms
def models_dir() -> Path:
    """``models/mechanisms`` of the source checkout (the shipped TOML files)."""
    return Path(__file__).resolve().parents[1] / "models" / "mechanisms"


def shipped_models() -> dict[str, dict]:
    """Shipped models by name: ``description`` and ``source`` (builder and/or file).

    The builders of :data:`pkm_pin.builders.MECHANISMS` and the files
    ``models/mechanisms/*.toml`` (same name for the same mechanism).
    """
    from .builders import DESCRIPTIONS, MECHANISMS
    from .io import tomllib

    models = {name: {"description": DESCRIPTIONS.get(name, ""), "builder": True, "file": None}
              for name in MECHANISMS}
    folder = models_dir()
    for path in sorted(folder.glob("*.toml")) if folder.is_dir() else []:
        entry = models.setdefault(path.stem, {"description": "", "builder": False, "file": None})
        entry["file"] = str(path)
        if not entry["description"]:
            try:
                entry["description"] = str(tomllib.loads(path.read_text()).get("description", ""))
            except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError):
                entry["description"] = "(unreadable file)"
    return models


def load(spec: str | None, closures: str | None = None, output: str | None = None,
         point: bool | None = None, backend: str | None = None):
    """The mechanism named by ``spec``: a file path, a shipped model name, or ``None``
    (the 3-RPR of seed 000, Michalková & Guldan, see docs/references.md).

    Args:
        closures, output, point: For a linkage file, as :func:`pkm_pin.load_mechanism`.
        backend: ``"legs"`` or ``"general"``, as :func:`pkm_pin.load_mechanism`.

    Returns:
        A :class:`~pkm_pin.Mechanism` (read by the general backend for a ``.urdf``,
        ``.xml`` / ``.mjcf`` or pinned ``.toml`` file, another output or ``--backend
        general``).

    Raises:
        MechanismFileError: the file is missing or wrong (or the options do not apply).
        InputError: ``spec`` is neither a file nor a shipped model.
    """
    from .builders import MECHANISMS
    from .io import general_reading, load_mechanism, other_output
    from .mechanism import Mechanism

    options = {"closures": closures, "output": output, "point": point}
    if spec is None or (spec in MECHANISMS and not _is_file(Path(spec))):
        if closures is not None:
            raise InputError("--closures: for a .urdf file; a shipped mechanism holds its "
                             "own closures")
        mech = MECHANISMS["rpr3" if spec is None else spec]().build()
        if output is not None or point is not None:
            link = other_output(mech, output, point)
        elif backend == "general":
            link = general_reading(mech)
        else:
            return mech
        return Mechanism.of_linkage(link, description=mech.description)
    path = Path(spec)
    if _is_file(path) or spec.endswith(LINKAGE_SUFFIXES + (".toml",)) or "/" in spec \
            or "\\" in spec:
        return load_mechanism(path, backend=backend, **options)
    shipped = models_dir() / f"{spec}.toml"
    if _is_file(shipped):
        return load_mechanism(shipped, backend=backend, **options)
    shown = spec if len(spec) <= 80 else spec[:77] + "..."
    raise InputError(f"{shown!r} is neither a mechanism file nor a shipped model; the shipped "
                     f"models are: {', '.join(sorted(shipped_models()))} (see 'pkm-pin list')")


def _json(data) -> str:
    """Strict JSON of a report (:func:`pkm_pin.report.strict_json`: no NaN/Infinity)."""
    from .report import strict_json

    return strict_json(data)


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False for names the OS refuses (too long, NUL byte)."""
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def _load(args, spec: str | None = None):
    """:func:`load` of ``spec`` (default ``args.mechanism``) with the linkage options."""
    return load(args.mechanism if spec is None else spec, getattr(args, "closures", None),
                getattr(args, "output", None), getattr(args, "point", None),
                getattr(args, "backend", None))


def _pose_dict(pose) -> dict:
    import pinocchio as pin

    return {"xyz": pose.translation.tolist(), "rpy": pin.rpy.matrixToRpy(pose.rotation).tolist()}


def _pose_text(pose) -> str:
    d = _pose_dict(pose)
    return f"xyz {_fmt(d['xyz'])}  rpy {_fmt(d['rpy'])}"


def _fmt(values) -> str:
    return "[" + ", ".join(f"{v + 0.0:.6g}" for v in np.round(values, 12)) + "]"


def analysis_report(analysis) -> dict:
    """Plain-data summary of an analysis (see :func:`pkm_pin.report.report_data`)."""
    from .report import report_data

    return report_data(analysis)


# ------------------------------------------------------------------- commands
def cmd_list(args) -> int:
    """Print the shipped models, one line each."""
    models = shipped_models()
    if args.json:
        print(_json(models))
        return 0
    width = max(len(n) for n in models)
    for name, m in sorted(models.items()):
        print(f"{name:<{width}}  {m['description']}")
    return 0


def cmd_analyze(args) -> int:
    """Report of one assembly (default: home; ``--q``, ``--pose``, ``--at``) as text or
    JSON, optionally as Markdown: the one report of :mod:`pkm_pin.report`, whichever
    backend reads the mechanism."""
    from . import report

    mech = _load(args)
    assembly = _assembly(args, mech)
    data = report.report_data(mech, assembly, plots=args.plots or ())
    if args.markdown:
        _write_text(args.markdown, report.markdown(data=data))
    if args.json:
        print(_json(data))
    else:
        likely, frames = report.output_hint(mech.general.model, assembly.q)
        print(report.text(data, frames, likely))
        if args.markdown:
            print(f"markdown           {args.markdown}")
    return 0


def _assembly(args, mech):
    """The mechanism assembled as the options say, whichever backend reads it: ``--q``
    (forward kinematics from home), ``--pose`` / ``--at`` (a full or partial output
    pose: :meth:`Mechanism.assembly_at`), else home."""
    pose, q = _platform_pose(args), getattr(args, "q", None)
    if q is not None:
        if pose is not None:
            raise InputError("give --q (actuated values) or --pose / --at (output pose), "
                             "not both")
        return mech.forward_kinematics(mech.check_actuated(q, "--q"), mech.home_assembly)
    return mech.assembly_at(pose)


def cmd_check(args) -> int:
    """Load a mechanism file, assemble it at home and analyse it; report problems. One
    path for every mechanism: the tree's lines read through :attr:`Mechanism.general`
    (closures, idle motions, duplicate closures, the output choice, the independent
    sub-mechanisms), the numbers of the backend that reads it, and the per-leg engine's
    cross-check with the papers' formulas where they exist."""
    from .analysis import LegsAnalysis
    from .crosscheck import crosscheck
    from .io import load_mechanism
    from .linkage import LoopClosureError
    from .model.closure_model import duplicate_closures
    from .report import optional
    from .submechanisms import analysed

    path = Path(args.file)
    if not _is_file(path) and _is_file(models_dir() / f"{args.file}.toml"):
        path = models_dir() / f"{args.file}.toml"
    mech = load_mechanism(path, closures=args.closures, output=args.output, point=args.point,
                          backend=args.backend)
    link, model = mech.general, mech.general.model
    closures = ", ".join(f"{c.name}: {c.kind}" for c in model.closures) or (
        "none: a tree, analysed as a serial chain")
    per_leg = mech.backend == "legs"
    legs = (f"; read per leg: {len(mech.legs)} legs "
            f"({', '.join(f'{leg.name}: {leg.nv} joints' for leg in mech.legs)})"
            if per_leg else "")
    print(f"ok    loads: {mech.name!r}, {model.tree.njoints - 1} joints (nq {model.nq}, "
          f"nv {model.nv}), {len(model.closures)} closure{'s' * (len(model.closures) != 1)} "
          f"({closures}), {mech.n_actuated} actuated "
          f"({', '.join(mech.actuated_names) or 'none'}), output {link.output!r} "
          f"({'point' if model.output_point else 'body'}){legs}")
    try:
        asm = mech.home_assembly
    except LoopClosureError as e:
        raise InputError(f"{path}: {e}") from e
    print(f"ok    assembles {'at home' if per_leg else 'from the reference configuration'} "
          f"(closure residual {asm.residual:.2g}); output at {_pose_text(asm.output_pose)}")
    for note in model.notes:
        print(f"info  {note}")
    _check_output_choice(link, asm)
    an = mech.analyze(asm)
    mob = an.mobility
    print(f"ok    mobility: DOF {mob.dof}, idle DOF {an.idle_dof}, Grübler count "
          f"{an.grubler}, redundant {'constraints' if per_leg else 'closure equations'} "
          f"{an.redundant_constraints}, output motion {an.motion_type}, singularity "
          f"{an.singularity}")
    for motion in mob.idle_motions:
        print(f"info  idle motion (actuators locked): {motion}")
    warnings = _check_actuators(mech, an)
    if mob.singular:
        warnings.append(mob.singular_words)
    warnings += [f"closure {a!r} repeats {b!r}: its rows are redundant (remove one)"
                 for a, b in duplicate_closures(model.closures)]
    failed: dict = {}
    parts = optional("submechanisms", lambda: analysed(link, asm.q), failed)
    warnings += [f"sub-mechanisms not computed ({why})" for why in failed.values()]
    if parts:
        warnings += _check_submechanisms(link, an, parts)
    elif an.singularity != "none":
        warnings.append(f"the reference assembly is a type {an.singularity} singularity "
                        f"({_indices_words(an.indices)})")
    checks = crosscheck(an) if isinstance(an, LegsAnalysis) else None
    if checks is not None:
        worst = max(checks.values())
        if worst > CROSSCHECK_TOL:
            warnings.append(f"the hand-written formulas disagree with the analysis by {worst:.2g}")
        else:
            print(f"ok    cross-check with the hand-written formulas: {worst:.2g}")
    for w in warnings:
        print(f"warn  {w}")
    print(f"{path}: " + (f"{len(warnings)} warning(s)" if warnings else "fine"))
    return 1 if warnings else 0


def _check_actuators(mech, an) -> list[str]:
    """``check``'s warnings on the actuators: none, too few to drive the output, or some
    that depend on the others (redundant actuation), and a mechanism that cannot move."""
    mob, warnings = an.mobility, []
    if mob.dof == 0:
        warnings.append("the mechanism cannot move here (DOF 0)")
    if not mech.n_actuated:
        warnings.append("no actuated joint")
    elif len(mob.independent_actuators) < an.output_dof:
        warnings.append(f"{len(mob.independent_actuators)} actuated joints for "
                        f"{an.output_dof} DOF: fewer actuators than degrees of freedom of "
                        "the output")
    dependent = [a for a in mech.general.actuated if a not in mob.independent_actuators]
    if dependent:
        warnings.append(f"actuated joints {', '.join(dependent)} depend on the others "
                        "(redundant actuation)")
    return warnings


def _check_output_choice(link, asm) -> None:
    """``check``'s line on an output the file did not name: chosen by the default rule
    (:mod:`pkm_pin.output_choice`), with the others that fit as well and how to pick one."""
    from .report import output_hint

    if link.model.output_named:
        return
    likely, _ = output_hint(link.model, asm.q)
    others = [f for f in likely if f != link.output]
    print(f"info  output {link.output!r}: not named in the file, chosen by the default rule "
          "(the body the mechanism exists to move)"
          + (f"; as likely: {', '.join(others)} (--output FRAME)" if others else ""))


def _indices_words(indices: dict) -> str:
    """``indices type_I 0, type_II undefined, …`` (undefined: not finite)."""
    return "indices " + ", ".join(
        f"{k} {f'{v:.2g}' if np.isfinite(v) else 'undefined'}" for k, v in indices.items())


def _check_submechanisms(link, an, parts) -> list[str]:
    """``check`` of a linkage with several independent sub-mechanisms (a biped's legs):
    one line each (joints, actuators, output, DOF, idle DOF, motion, singularity), the
    whole's one-output singularity class as information (another sub-mechanism's
    actuators do not move that output: type I by construction), and the warnings of
    each sub-mechanism (DOF 0, a singular reference assembly with its own output)."""
    print(f"info  {len(parts)} independent sub-mechanisms (no movable joint shared), each "
          "checked with its own output; 'fk --sub K' drives one alone")
    warnings = []
    for k, (sub, a) in enumerate(parts):
        print(f"ok    sub-mechanism [{k}] {sub.name}: {sub.model.tree.njoints - 1} joints, "
              f"{len(sub.actuated)} actuated ({', '.join(sub.actuated) or 'none'}), output "
              f"{sub.output!r}: DOF {a.dof}, idle DOF {a.idle_dof}, output motion "
              f"{a.motion_type}, singularity {a.singularity}")
        if a.dof == 0:
            warnings.append(f"sub-mechanism {sub.name} cannot move here (DOF 0)")
        if a.singularity != "none":
            warnings.append(f"sub-mechanism {sub.name}: the reference assembly is a type "
                            f"{a.singularity} singularity of its output {sub.output!r} "
                            f"({_indices_words(a.indices)})")
    if an.singularity != "none":
        print(f"info  the whole read with the one output {link.output!r} is type "
              f"{an.singularity} ({_indices_words(an.indices)}), a class of one output "
              "that the other sub-mechanisms do not move; each sub-mechanism is judged "
              "with its own output")
    return warnings


def cmd_fk(args) -> int:
    """Forward kinematics, one path for every mechanism: every joint and the output pose
    for the actuated values (the branch nearest home, as ``ik`` and ``analyze --q``), or
    every assembly mode found (``--all``); with several independent sub-mechanisms (a
    biped's legs) each one's output pose too, and ``--sub K``: the values are
    sub-mechanism K's alone (:func:`_fk_sub`)."""
    from .report import fk_submechanisms_data, fk_text, optional

    mech = _load(args)
    failed: dict = {}
    subs = _submechanisms_or_why(mech, args.sub, failed)
    if args.all:
        if args.sub is not None:
            raise InputError("--all and --sub K: give the values of the whole mechanism "
                             "for every assembly mode")
        return _fk_modes(args, mech)
    if args.sub is not None:
        assembly = _fk_sub(mech, subs, args.sub, args.q)
    else:
        if len(args.q) != mech.n_actuated and len(subs) > 1:
            raise InputError(f"{len(args.q)} actuated values given, {mech.n_actuated} "
                             f"expected ({', '.join(mech.actuated_names)}); for one "
                             "independent sub-mechanism alone give --sub K and its values: "
                             + _subs_words(subs))
        assembly = mech.forward_kinematics(mech.check_actuated(args.q),
                                           guess=mech.home_assembly)
    data = _assembly_data(mech, assembly)
    data["submechanisms"] = optional(
        "submechanisms", lambda: fk_submechanisms_data(mech, subs, assembly), failed)
    data["failed_sections"] = failed
    print(_json(data) if args.json else fk_text(data))
    return 0


def _assembly_data(mech, assembly) -> dict:
    """:func:`pkm_pin.report.assembly_data` of any mechanism's assembly (the tree read
    through :attr:`Mechanism.general`), the actuated names in the order of the values,
    and each leg's configuration (``leg_q``) where the mechanism is read per leg."""
    from .report import assembly_data

    data = assembly_data(mech.general, assembly)
    data["backend"], data["actuated"] = mech.backend, list(mech.actuated_names)
    if mech.backend == "legs":
        data["leg_q"] = {leg.name: q.tolist() for leg, q in zip(mech.legs, assembly.leg_q)}
    return data


def _fk_modes(args, mech) -> int:
    """``fk --all``: every assembly mode found for the actuated values
    (:meth:`Mechanism.forward_kinematics_all`), nearest home first; one line each (the
    output pose), or the list of their assemblies in JSON."""
    q = mech.check_actuated(args.q)
    found = mech.forward_kinematics_all(q, starts=args.starts, seed=args.seed)
    rows = [_assembly_data(mech, a) for a in found]
    if args.json:
        print(_json(rows))
        return 0
    print(f"mechanism  {mech.name}")
    print(f"actuated   {', '.join(mech.actuated_names)} = {_fmt(q)}")
    if not found:
        print("no assembly mode found")
    for i, a in enumerate(found):
        print(f"{f'mode {i + 1}':<10} {_pose_text(a.output_pose)}")
    return 0


def cmd_sensitivity(args) -> int:
    """Output error per unit geometric error (joint origins and axes, bases, anchors or
    closure frames), at home or after forward kinematics (``--q``), largest first."""
    mech = _load(args)
    where = mech.home_assembly
    if args.q is not None:
        where = mech.forward_kinematics(mech.check_actuated(args.q, "--q"), guess=where)
    if args.top < 1:
        raise InputError(f"--top must be at least 1, got {args.top}")
    sens = mech.sensitivity(where, args.parameters)
    data = sensitivity_data(sens, mech.characteristic_length)
    data["mechanism"] = mech.name
    if args.json:
        print(_json(data))
        return 0
    print(sensitivity_text(data, args.top))
    return 0


def sensitivity_data(sens, length: float) -> dict:
    """Plain data of a :class:`~pkm_pin.sensitivity.Sensitivity`: the output origin
    ``point``, the characteristic ``length``, and per parameter (largest effect first:
    ``|δp| + L |δθ|`` per unit error) its ``twist`` at the output origin ``(δθ; δp)`` per
    unit error, ``position_gain`` ``|δp|`` and ``rotation_gain`` ``|δθ|`` and whether the
    rigid mechanism can absorb it (``compatible``)."""
    M = sens.point_matrix()
    gains = tuple(np.where(g > 1e-12 * g.max(initial=0.0), g, 0.0)  # round-off shown as 0
                  for g in (np.linalg.norm(M[3:], axis=0), np.linalg.norm(M[:3], axis=0)))
    order = np.argsort(-(gains[0] + length * gains[1]), kind="stable")
    bad = set(sens.incompatible)
    return {"point": sens.assembly.pose.translation.tolist(), "length": float(length),
            "parameters": [{"name": sens.parameters[k], "twist": M[:, k].tolist(),
                            "position_gain": float(gains[0][k]),
                            "rotation_gain": float(gains[1][k]),
                            "compatible": sens.parameters[k] not in bad} for k in order]}


def sensitivity_text(data: dict, top: int) -> str:
    """The text of :func:`sensitivity_data`: the ``top`` largest effects, then the
    parameters the mechanism cannot absorb."""
    rows = [r for r in data["parameters"] if r["compatible"]]
    bad = [r["name"] for r in data["parameters"] if not r["compatible"]]
    width = max([len(r["name"]) for r in rows[:top]] + [9])
    lines = [f"mechanism  {data['mechanism']}",
             f"output     at {_fmt(data['point'])}; per unit error of each parameter (m or "
             "rad), actuated joints held",
             f"{'parameter':<{width}}  {'|δp| [m/unit]':>14}  {'|δθ| [rad/unit]':>15}"]
    lines += [f"{r['name']:<{width}}  {r['position_gain']:>14.4g}  {r['rotation_gain']:>15.4g}"
              for r in rows[:top]]
    if len(rows) > top:
        lines.append(f"... {len(rows) - top} more (--top N, --json)")
    if bad:
        lines.append(f"cannot absorb {len(bad)} (an error opens a loop of the rigid "
                     f"mechanism): {', '.join(bad[:8])}" + (" ..." if len(bad) > 8 else ""))
    return "\n".join(lines)


def _submechanisms_or_why(link, k: int | None, failed: dict | None = None) -> list:
    """:meth:`Mechanism.submechanisms` (``[mech]`` for a platform machine) as an optional section
    (:func:`pkm_pin.report.optional`: ``[link]`` with the error in ``failed`` when the
    split fails), or, for ``--sub K`` (``k`` given), the error in one line."""
    from .report import optional

    failed = {} if failed is None else failed
    subs = optional("submechanisms", link.submechanisms, failed)
    if subs is None and k is not None:
        raise InputError(f"--sub {k}: the sub-mechanisms of {link.name!r} could not be "
                         f"computed ({failed['submechanisms']})")
    return [link] if subs is None else subs


def _pick_sub(link, subs, k: int):
    """Sub-mechanism ``k`` of ``subs`` (``link``'s), or the error of ``--sub K``."""
    if len(subs) <= 1:
        raise InputError(f"--sub {k}: {link.name!r} is one mechanism (no independent "
                         "sub-mechanisms); leave --sub out")
    if not 0 <= k < len(subs):
        raise InputError(f"--sub {k}: {link.name!r} has {len(subs)} independent "
                         f"sub-mechanisms, numbered 0 to {len(subs) - 1}: "
                         + _subs_words(subs))
    return subs[k]


def _subs_words(subs) -> str:
    """``0: name (n values: a, b, …); 1: …`` for an error message."""
    return "; ".join(f"{k}: {s.name} ({len(s.actuated)} values: {', '.join(s.actuated)})"
                     for k, s in enumerate(subs))


def _fk_sub(link, subs, k: int, values):
    """The whole linkage assembled with sub-mechanism ``k``'s actuated joints at
    ``values`` and every other actuated joint at the reference assembly: the
    sub-mechanism's forward kinematics from its reference, put in the whole tree
    (:func:`pkm_pin.submechanisms.embed`), then the whole's (its targets met there
    already: it checks the closure of every loop)."""
    from .submechanisms import embed

    sub = _pick_sub(link, subs, k)
    if len(values) != len(sub.actuated):
        raise InputError(f"--sub {k}: {len(values)} actuated values given, "
                         f"{len(sub.actuated)} expected ({', '.join(sub.actuated)})")
    one = sub.forward_kinematics(sub.check_actuated(values, "Q"), guess=sub.home_assembly)
    home = link.home_assembly
    q = embed(link, sub, one.q, home.q)
    targets = dict(zip(link.actuated, home.q_actuated))
    targets.update(zip(sub.actuated, one.q_actuated))
    return link.forward_kinematics([targets[n] for n in link.actuated], guess=q)


def cmd_ik(args) -> int:
    """Inverse kinematics, one path for every mechanism: the assembly whose output
    reaches the pose (``--pose``; ``--at``: a partial pose, the other coordinates free;
    default the home pose), its actuated values, every joint and the output pose; every
    working mode with ``--all``."""
    from .assembly import as_pose
    from .report import fk_text, pose_dict

    mech = _load(args)
    given = _platform_pose(args)
    if args.all:
        return _ik_modes(args, mech, given)
    assembly = _assembly(args, mech)
    data = _assembly_data(mech, assembly)
    if isinstance(given, dict):  # the other coordinates free: the pose they completed
        data["given"] = given
        head = (f"given      {', '.join(f'{k}={v:g}' for k, v in given.items())} (the "
                f"other coordinates free)\npose       {_pose_text(assembly.output_pose)}")
    else:
        data["target"] = pose_dict(mech.home_assembly.output_pose if given is None
                                   else as_pose(given))
        head = (f"target     xyz {_fmt(data['target']['xyz'])}  "
                f"rpy {_fmt(data['target']['rpy'])}")
    if args.json:
        print(_json(data))
        return 0
    print(head)
    print(fk_text(data))
    return 0


def _ik_modes(args, mech, given) -> int:
    """``ik --all``: every working mode at the pose (default home;
    :meth:`Mechanism.inverse_kinematics_all`), the home one first: the actuated values
    of each, and in JSON the assembly of each too (``modes``)."""
    pose = mech.home_assembly.output_pose if given is None else given
    found = mech.inverse_kinematics_all(pose)
    values = [np.asarray(a.q_actuated, dtype=float).tolist() for a in found]
    if args.json:
        print(_json({"actuated": list(mech.actuated_names), "q_actuated": values,
                     "pose": _pose_dict(found[0].output_pose) if found else None,
                     "modes": [_assembly_data(mech, a) for a in found]}))
        return 0
    print(f"mechanism  {mech.name}")
    if isinstance(given, dict):
        print(f"given      {', '.join(f'{k}={v:g}' for k, v in given.items())}")
    if found:
        print(f"pose       {_pose_text(found[0].output_pose)}")
    print(f"actuated   {', '.join(mech.actuated_names)}")
    for i, m in enumerate(values):
        print(f"{f'mode {i + 1}':<10} {_fmt(m)}")
    return 0


def _grid_axes(mech, axes, home: np.ndarray, ranges, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The values of the two varied coordinates: ``ranges`` (A B C D), default home ±
    the characteristic length (x, y, z) or ± 0.5 rad (angles)."""
    i, j = axes
    if ranges is None:
        half = [mech.characteristic_length if k < 3 else MAP_ANGLE_HALF_RANGE for k in (i, j)]
        ranges = [home[i] - half[0], home[i] + half[0], home[j] - half[1], home[j] + half[1]]
    a, b, c, d = (float(x) for x in ranges)
    if not all(np.isfinite([a, b, c, d])) or a == b or c == d:
        raise InputError(f"--range needs finite bounds with A != B and C != D, got {ranges}")
    if not 2 <= n <= 2000:
        raise InputError(f"--n must be between 2 and 2000, got {n}")
    return np.linspace(a, b, n), np.linspace(c, d, n)


#: Default half range [rad] of an angle varied by ``map --axes``.
MAP_ANGLE_HALF_RANGE = 0.5


def map_poses(mech, axes, ranges, n: int, at=None):
    """The grid of a platform map over two pose coordinates ``axes`` (names), the
    coordinates of ``at`` ({name: value}) given, as many others as the mechanism's DOF
    needs held at home (:func:`pkm_pin.position.coordinate_plan` at the home assembly),
    the rest solved for.

    Returns:
        ``(u, v, poses, held)``: the column and row values, the poses in row-major order
        (an (N, 6) array when every coordinate is given or held, else a list of partial
        poses for :meth:`Mechanism.sweep`), and the held coordinates {name: home value}.

    Raises:
        InputError: a varied coordinate also in ``at``; DependentCoordinates: the
            coordinates are not independent for this mechanism.
    """
    from .position import coordinate_plan
    from .solve import CoordinateSystem, pose_coordinates

    at = dict(at or {})
    both = [k for k in axes if k in at]
    if both:
        raise InputError(f"--at/--fixed {both[0]}: {both[0]} is varied over the map")
    home_asm = mech.home_assembly
    home = pose_coordinates(home_asm.pose)
    idx = tuple(POSE_NAMES.index(k) for k in axes)
    u, v = _grid_axes(mech, idx, home, ranges, n)
    system = CoordinateSystem(mech, home_asm.pose, home_asm.leg_q)
    _, held_rows, _ = coordinate_plan(mech, system, list(axes) + list(at))
    held = {POSE_NAMES[k]: float(home[k]) for k in held_rows}
    fixed = {**at, **held}
    V, U = np.meshgrid(v, u, indexing="ij")
    if len(fixed) + 2 == 6:
        poses = np.tile(home, (U.size, 1))
        for name, value in fixed.items():
            poses[:, POSE_NAMES.index(name)] = value
        poses[:, idx[0]], poses[:, idx[1]] = U.ravel(), V.ravel()
        return u, v, poses, held
    poses = [{axes[0]: float(a), axes[1]: float(b), **fixed} for a, b in zip(U.ravel(),
                                                                             V.ravel())]
    return u, v, poses, held


def _map_reading(args, mech) -> tuple:
    """``(what, mechanism, per_leg)``: what ``map`` sweeps, decided here only.

    * ``"actuated"``: the tree's sweep over actuated coordinates (``--actuated``,
      ``--sub K``, a mechanism read over its tree without pose options, or one with fewer
      than two independent pose coordinates); a per-leg mechanism is swept through its
      tree (:func:`pkm_pin.io.general_reading`) and ``per_leg`` is that mechanism, whose
      own classes and indices the map gives (else None);
    * ``"poses"``: pose coordinates (``--axes``/``--plane``/``--at``, default
      :func:`_default_axes`) through the mechanism's own sweep: the per-leg engine's
      chunks (partial poses completed on the motion), or, on a mechanism read over its
      tree, the output's inverse kinematics walked from grid point to grid point
      (:func:`_map_tree_poses`)."""
    from .io import general_reading

    actuated = args.actuated is not None or args.sub is not None
    pose_options = args.axes is not None or args.plane is not None or args.at is not None
    if actuated and pose_options:
        option = "--actuated" if args.actuated is not None else "--sub K"
        raise InputError(f"{option} maps over actuated coordinates; --axes/--plane/--at "
                         "over pose coordinates: give one or the other")
    if mech.backend == "general":
        return ("poses" if pose_options else "actuated"), mech, None
    if not actuated and not pose_options and not args.fixed:
        axes = _default_axes(mech)
        if axes is None:
            print(f"note       {mech.name} has fewer than 2 independent pose coordinates: "
                  "mapped over its actuated coordinates")
            actuated = True
        elif axes != ("x", "y"):
            args.axes = list(axes)
    if not actuated:
        return "poses", mech, None
    return "actuated", general_reading(mech), mech  # over actuated coordinates: the tree


def _default_axes(mech) -> tuple[str, str] | None:
    """The pose coordinates a platform ``map`` varies when none is given: x and y where
    they are independent coordinates of ``mech`` at home, else the first two independent
    ones (x, z for a five-bar in the xz plane); ``None`` when it has fewer than two (a
    four-bar: its map is over its actuated coordinates)."""
    from .position import DependentCoordinates, coordinate_plan
    from .solve import CoordinateSystem

    try:
        home = mech.home_assembly
        coordinate_plan(mech, CoordinateSystem(mech, home.pose, home.leg_q), ["x", "y"])
    except DependentCoordinates as e:
        return tuple(e.independent[:2]) if len(e.independent) >= 2 else None
    except PkmError:  # the map itself then says what is wrong
        pass
    return ("x", "y")


def _map_axes_names(args) -> tuple[str, str]:
    """The two varied coordinates of a platform map: ``--axes``, or ``--plane`` (xy)."""
    if args.axes is not None and args.plane is not None:
        raise InputError("give --axes NAME NAME or --plane, not both")
    if args.axes is None:
        return tuple(POSE_NAMES[k] for k in PLANES[args.plane or "xy"])
    names = tuple(a.strip().lower() for a in args.axes)
    if len(names) != 2 or len(set(names)) != 2 or any(a not in POSE_NAMES for a in names):
        raise InputError(f"--axes takes two distinct coordinates of {', '.join(POSE_NAMES)}; "
                         f"got {' '.join(args.axes)}")
    return names


def cmd_map(args) -> int:
    """Sweep a workspace slice over two pose coordinates (partial poses completed on the
    mechanism's motion); write PREFIX.npz and the two PNG maps."""
    from .plots import save_maps

    what, mech, per_leg = _map_reading(args, _load(args))
    if what == "poses" and mech.backend == "general":
        return _map_tree_poses(args, mech)
    if what == "actuated":
        subs = _submechanisms_or_why(mech, args.sub)
        if args.sub is not None:
            return _map_actuated(args, _pick_sub(mech, subs, args.sub), None if len(subs) > 1
                                else per_leg)
        if len(subs) > 1:
            words = "; ".join(f"{k}: {s.name}, output {s.output}" for k, s in enumerate(subs))
            print(f"note       {len(subs)} independent sub-mechanisms ({words}): "
                  f"the classes below are those of the one output {mech.output!r}, which "
                  "the others' motors do not move (type I); --sub K maps one with its own "
                  "output")
        return _map_actuated(args, mech, per_leg)
    axes, tag, prefix, at = _pose_map_options(args)
    u, v, poses, held = map_poses(mech, axes, args.range, args.n, at)
    cp = _checkpoint(args, prefix, {
        "study": "map", "axes": list(axes), "at": {k: float(x) for k, x in sorted(at.items())},
        "u": u, "v": v, "chunk_size": int(args.chunk_size)}, len(poses), mech.n_actuated)
    result = _sweep_map(mech, args, poses, u.size, v.size, cp)
    shape = (v.size, u.size)
    i, j = (POSE_NAMES.index(a) for a in axes)
    data = {k: a.reshape(shape + a.shape[1:]) for k, a in result.arrays().items()}
    units = [getattr(mech, "length_unit", "m")] * 3 + ["rad"] * 3
    data.update(u=u, v=v, plane=np.array("".join(axes) if args.axes is None else tag),
                axes=np.array(axes),
                labels=np.array([f"{POSE_NAMES[i]} [{units[i]}]", f"{POSE_NAMES[j]} [{units[j]}]"]),
                mechanism=np.array(mech.name), actuated=np.array(mech.actuated_names),
                failure_index=np.array([f[0] for f in result.failures], dtype=int),
                failure_reason=np.array([f[1] for f in result.failures], dtype=str))
    npz = _save_npz(prefix, data)
    pngs = save_maps(data, prefix, title=mech.name)
    cp.remove()  # the outputs are written: the partial results are not needed any more
    _print_map(mech, axes, u, v, at, held, result, isinstance(poses, list))
    for path in [npz, *pngs]:
        print(f"wrote      {path}")
    return 0


def _pose_map_options(args) -> tuple:
    """``(axes, tag, prefix, at)`` of a map over two pose coordinates: their names, the
    tag of the output files, the output prefix, and the coordinates given by ``--fixed``
    and ``--at`` ({name: value})."""
    axes = _map_axes_names(args)
    tag = args.plane or "".join(axes) if args.axes is None else "_".join(axes)
    prefix = _map_prefix(args, tag)
    if args.range is not None and len(args.range) != 4:
        raise InputError(f"--range takes 4 bounds A B C D for two coordinates, got "
                         f"{len(args.range)}")
    at = at_values(args.fixed, "--fixed")
    for name, value in at_values(args.at).items():
        if name in at:
            raise InputError(f"{name} is given by both --at and --fixed")
        at[name] = value
    return axes, tag, prefix, at


def _sweep_map(mech, args, poses, n_u: int, n_v: int, cp=None):
    """The sweep of a map's poses (row-major); partial poses completed in snake order,
    each from its neighbour, the result given back in row-major order; chunks of
    ``--chunk-size`` poses recorded in the checkpoint ``cp`` (``PREFIX.partial.npz``)."""
    from .checkpoint import graceful_stop

    executor = None
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        executor = ProcessPoolExecutor(args.jobs)
    order = _snake(n_u, n_v) if isinstance(poses, list) else np.arange(len(poses))
    ordered = [poses[k] for k in order] if isinstance(poses, list) else poses
    try:
        with graceful_stop(_stopping):
            result = mech.sweep(ordered, executor=executor, progress=not args.quiet,
                                chunk_size=args.chunk_size,
                                checkpoint=cp.stage("cells") if cp is not None else None)
    except KeyboardInterrupt as e:
        _attach(e, cp)
        raise
    finally:
        if executor is not None:
            executor.shutdown(cancel_futures=True)
    return result.unordered(order) if isinstance(poses, list) else result


def _save_npz(prefix: Path, data: dict) -> Path:
    """``data`` saved as ``<prefix>.npz`` (compressed; a temporary name renamed: never
    a truncated file); an unwritable place is an :class:`InputError`."""
    from .checkpoint import atomic_savez

    npz = prefix.with_name(prefix.name + ".npz")
    try:
        atomic_savez(npz, compressed=True, **data)
    except OSError as e:
        raise InputError(f"cannot write {npz}: {e.strerror or e}") from e
    return npz


def _print_map(mech, axes, u, v, at, held, result, completed: bool) -> None:
    """The text summary of a platform map: the slice, what was given, held and solved
    for, how many poses assembled, and why the others did not."""
    n_ok, total = int(result.ok.sum()), len(result.ok)
    counts = {c: int(np.sum(result.singularity == c)) for c in ("I", "II", "III")}
    print(f"mechanism  {mech.name}")
    print(f"slice      {axes[0]} in [{u[0]:g}, {u[-1]:g}], {axes[1]} in [{v[0]:g}, {v[-1]:g}], "
          f"{u.size} × {v.size} poses")
    fixed = [f"{k}={x:g}" for k, x in at.items()] + [f"{k}={x:g} (home)" for k, x in
                                                      held.items()]
    if fixed:
        print(f"fixed      {', '.join(fixed)}")
    if completed:
        solved = [k for k in POSE_NAMES if k not in axes and k not in at and k not in held]
        print(f"solved for {', '.join(solved)} (on the mechanism's motion)")
    print(f"assembled  {n_ok} of {total}; singular grid points: "
          + ", ".join(f"type {k} {c}" for k, c in counts.items()))
    if result.failures:
        first = result.failures[0][1]
        not_completed = sum(r.startswith("not completed") for _, r in result.failures)
        what = f" ({not_completed} not completed)" if not_completed else ""
        print(f"failed     {len(result.failures)}{what}; e.g. {first[:200]}")
    if n_ok == 0:
        print("warning    no pose of this slice assembled")


def _map_prefix(args, tag: str) -> Path:
    """The output prefix of ``map`` (default ``map_NAME_TAG``; ``--resume PREFIX``), its
    folder checked (it exists, is a folder, is writable)."""
    return _out_prefix(args, f"map_{_slug(args.mechanism)}_{tag}")


def _out_prefix(args, default: str) -> Path:
    """The output prefix: ``--out``, or ``--resume`` (the same when both are given), or
    ``default``; an :class:`InputError` before any work when its folder is missing, is
    not a folder or cannot be written."""
    from .checkpoint import check_writable

    resume = getattr(args, "resume", None)
    if resume is not None and args.out is not None and Path(resume) != Path(args.out):
        raise InputError(f"--resume {resume} continues the study whose outputs go to "
                         f"{resume}; --out {args.out} differs (give one of them)")
    prefix = Path(resume or args.out or default)
    option = "--resume" if resume is not None else "--out"
    check_writable(prefix.parent, f"{option} {prefix}")
    return prefix


def _checkpoint(args, prefix: Path, study: dict, N: int, n_actuated: int):
    """The :class:`~pkm_pin.checkpoint.Checkpoint` of a map or workspace at ``prefix``
    (``PREFIX.partial.npz``; ``--resume``: continue it): the study's identity is
    ``study``, the mechanism (name, file and the file's SHA-256) and the grid."""
    from .checkpoint import Checkpoint

    cp = Checkpoint(prefix, resume=getattr(args, "resume", None) is not None, keep=True,
                    identity=_mechanism_identity(args))
    cp.begin(study, need=3 * N * (8 * (8 + n_actuated) + 2))
    return cp


def _mechanism_identity(args) -> dict:
    """The mechanism of a study: as named, the file read and its SHA-256 (a shipped
    builder: its name)."""
    from .builders import MECHANISMS
    from .checkpoint import file_digest

    spec = args.mechanism
    path = Path(spec) if spec is not None else None
    if spec is None or (spec in MECHANISMS and not _is_file(path)):
        return {"mechanism": spec or "rpr3", "mechanism_file": None,
                "mechanism_sha256": None}
    if not _is_file(path):
        path = models_dir() / f"{spec}.toml"
    return {"mechanism": spec, "mechanism_file": str(path.resolve()),
            "mechanism_sha256": file_digest(path)}


def _stopping(signum: int) -> None:
    """Said on the first SIGINT / SIGTERM of a checkpointed study."""
    print("\npkm-pin: stopping after the current chunk (again to stop at once)",
          file=sys.stderr, flush=True)


def _attach(error: BaseException, cp) -> None:
    """An :class:`~pkm_pin.checkpoint.Interrupted` raised before its study's loop
    started is given the study's checkpoint (what an earlier stage saved)."""
    from .checkpoint import Interrupted

    if isinstance(error, Interrupted) and error.checkpoint is None:
        error.checkpoint = cp


def _map_axes(args, link) -> tuple[list[int], np.ndarray, list[np.ndarray]]:
    """The varied actuated coordinates of a linkage map (``--actuated``, default the first
    two), the values of all (``args.reference``, the reference assembly, and ``--fixed``
    NAME=VALUE) and the grid
    of each varied one (``--range``; default its joint limits, or the reference value
    ± π [rad] / ± the characteristic length [m] without limits)."""
    names = list(link.actuated)
    chosen = args.actuated or names[:2]
    unknown = [a for a in chosen if a not in names]
    if unknown or not chosen or len(set(chosen)) != len(chosen) or len(chosen) > 2:
        raise InputError(f"--actuated takes one or two distinct actuated joints of "
                         f"{', '.join(names) or '(none)'}; got {', '.join(chosen) or 'none'}")
    varied = [names.index(a) for a in chosen]
    base = args.reference.q_actuated.copy()
    for item in args.fixed or ():
        name, _, text = item.partition("=")
        if name.strip() not in names or names.index(name.strip()) in varied:
            raise InputError(f"--fixed takes NAME=VALUE with NAME an actuated joint that is "
                             f"not varied ({', '.join(names)}); got {item!r}")
        base[names.index(name.strip())] = _number(text, f"--fixed {name.strip()}")
    if args.range is not None and len(args.range) != 2 * len(varied):
        raise InputError(f"--range takes {2 * len(varied)} bounds for "
                         f"{', '.join(chosen)}, got {len(args.range)}")
    if not 2 <= args.n <= 2000:
        raise InputError(f"--n must be between 2 and 2000, got {args.n}")
    from .workspace import actuated_range

    grids = []
    for k, a in enumerate(varied):
        lo, hi = (args.range[2 * k:2 * k + 2] if args.range
                  else actuated_range(link, link.actuated[a], base[a]))
        if not np.isfinite([lo, hi]).all() or lo == hi:
            raise InputError(f"--range needs finite bounds with A != B, got {lo}, {hi}")
        grids.append(np.linspace(lo, hi, args.n))
    return varied, base, grids


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError as e:
        raise InputError(f"{what}: {text!r} is not a number") from e
    if not np.isfinite(value):
        raise InputError(f"{what}: the value must be finite, got {text!r}")
    return value


def _snake(n_u: int, n_v: int) -> np.ndarray:
    """Flat grid indices (row-major, row ``j`` at ``v[j]``) in snake order: each row
    walked the other way from the previous, so that neighbours follow each other."""
    rows = [np.arange(j * n_u, (j + 1) * n_u) for j in range(n_v)]
    return np.concatenate([r if j % 2 == 0 else r[::-1] for j, r in enumerate(rows)])


def _map_actuated(args, link, per_leg=None) -> int:
    """``map`` of a linkage over one or two actuated coordinates (grid walked in a snake
    from the reference assembly's branch, :meth:`Linkage.sweep`); writes PREFIX.npz and
    the PNG maps. For a mechanism read per leg (``per_leg``), the classes, the type I/II
    indices and the condition of ``A`` at each grid point are its own
    (:func:`_per_leg_classes`), as ``analyze`` reports them."""
    from .plots import save_class_maps

    if args.plane is not None:
        raise InputError("--plane is for platform mechanisms; a linkage is mapped over "
                         "actuated coordinates (--actuated NAME [NAME], --range)")
    from .checkpoint import graceful_stop

    if args.jobs > 1:
        raise InputError("--jobs: a map over actuated coordinates follows one branch from "
                         "grid point to grid point, so it runs in one process; leave "
                         "--jobs out")
    prefix = _map_prefix(args, "q")
    args.reference = link.assemble()
    varied, base, grids = _map_axes(args, link)
    u, v = grids[0], grids[1] if len(grids) == 2 else np.zeros(1)
    shape = (v.size, u.size)
    V, U = np.meshgrid(v, u, indexing="ij")
    Q = np.tile(base, (U.size, 1))
    Q[:, varied[0]] = U.ravel()
    if len(varied) == 2:
        Q[:, varied[1]] = V.ravel()
    order = _snake(u.size, v.size)
    cp = _checkpoint(args, prefix, {
        "study": "linkage map", "varied": [link.actuated[k] for k in varied], "base": base,
        "u": u, "v": v, "chunk_size": int(args.chunk_size)}, len(Q), len(link.actuated))
    try:  # the rows follow one branch: recorded in order, resumed from the last one
        with graceful_stop(_stopping):
            swept = link.sweep(Q[order], guess=args.reference, progress=not args.quiet,
                               chunk_size=args.chunk_size, checkpoint=cp.stage("sweep"))
    except KeyboardInterrupt as e:
        _attach(e, cp)
        raise
    data = {}
    for key in ("q_actuated", "converged", "q", "output_poses", "dof", "output_dof",
                "singularity", "type_I", "type_II", "condition", "forward", "inverse"):
        a = getattr(swept, key)
        grid = np.empty_like(a)
        grid[order] = a
        data[key] = grid.reshape(shape + a.shape[1:]) if len(varied) == 2 else grid
    if per_leg is not None:
        _per_leg_classes(per_leg, data)
    names = [link.actuated[k] for k in varied]
    data.update(u=u, labels=np.array([f"{n} [{_unit(link, k)}]" for n, k in zip(names, varied)]),
                mechanism=np.array(link.name), actuated=np.array(link.actuated),
                varied=np.array(names), output=np.array(link.output))
    if len(varied) == 2:
        data["v"] = v
    npz = _save_npz(prefix, data)
    pngs = save_class_maps(data, prefix, title=link.name)
    cp.remove()  # the outputs are written: the partial results are not needed any more
    ok, cls = data["converged"], data["singularity"]
    print(f"mechanism  {link.name}  (output {link.output})")
    print("grid       " + ", ".join(f"{n} in [{g[0]:g}, {g[-1]:g}]" for n, g in zip(names, grids))
          + f", {Q.shape[0]} points (snake order)")
    print(f"assembled  {int(ok.sum())} of {ok.size}; singular grid points: "
          + ", ".join(f"class {c} {int(np.sum(ok & (cls == c)))}" for c in ("I", "II", "III")))
    for path in [npz, *pngs]:
        print(f"wrote      {path}")
    return 0


def _map_tree_poses(args, mech) -> int:
    """``map --axes A B`` (or ``--plane``) of a mechanism read by the general backend: its
    output's inverse kinematics at each grid point of the two pose coordinates (a
    partial pose: those two, ``--at``/``--fixed`` ones, the others solved for nearest
    the last point, :meth:`~pkm_pin.linkage.Linkage.sweep`), walked in a snake from home;
    the classes and the forward/inverse indices drawn as an actuated map's
    (:func:`~pkm_pin.plots.save_class_maps`); checkpointed (``--resume``)."""
    from .checkpoint import graceful_stop
    from .plots import save_class_maps
    from .solve import pose_coordinates

    if args.jobs > 1:
        raise InputError("--jobs: a map of a mechanism read over its tree follows one "
                         "branch from grid point to grid point, so it runs in one "
                         "process; leave --jobs out")
    axes, tag, prefix, at = _pose_map_options(args)
    both = [k for k in axes if k in at]
    if both:
        raise InputError(f"--at/--fixed {both[0]}: {both[0]} is varied over the map")
    home = mech.home_assembly
    i, j = (POSE_NAMES.index(a) for a in axes)
    c = pose_coordinates(home.output_pose)
    mech.inverse_kinematics({axes[0]: c[i], axes[1]: c[j], **at}, home)  # dependent: refused
    u, v = _grid_axes(mech, (i, j), c, args.range, args.n)
    V, U = np.meshgrid(v, u, indexing="ij")
    poses = [{axes[0]: float(a), axes[1]: float(b), **at} for a, b in zip(U.ravel(),
                                                                         V.ravel())]
    order = _snake(u.size, v.size)
    cp = _checkpoint(args, prefix, {
        "study": "map", "axes": list(axes), "at": {k: float(x) for k, x in sorted(at.items())},
        "u": u, "v": v, "chunk_size": int(args.chunk_size)}, len(poses), mech.n_actuated)
    try:  # the points follow one branch: recorded in order, resumed from the last one
        with graceful_stop(_stopping):
            swept = mech.sweep([poses[k] for k in order], guess=home, progress=not args.quiet,
                               chunk_size=args.chunk_size, checkpoint=cp.stage("sweep"))
    except KeyboardInterrupt as e:
        _attach(e, cp)
        raise
    result = swept.unordered(order)
    shape = (v.size, u.size)
    data = {k: a.reshape(shape + a.shape[1:]) for k, a in result.arrays().items()}
    units = ["m"] * 3 + ["rad"] * 3
    data.update(u=u, v=v, plane=np.array("".join(axes) if args.axes is None else tag),
                axes=np.array(axes),
                labels=np.array([f"{POSE_NAMES[i]} [{units[i]}]", f"{POSE_NAMES[j]} [{units[j]}]"]),
                mechanism=np.array(mech.name), actuated=np.array(mech.actuated_names),
                output=np.array(mech.output),
                failure_index=np.array([f[0] for f in result.failures], dtype=int),
                failure_reason=np.array([f[1] for f in result.failures], dtype=str))
    data["converged"] = data["ok"]
    npz = _save_npz(prefix, data)
    pngs = save_class_maps(data, prefix, title=mech.name)  # classes and the tree's indices
    cp.remove()  # the outputs are written: the partial results are not needed any more
    _print_map(mech, axes, u, v, at, {}, result, True)
    for path in [npz, *pngs]:
        print(f"wrote      {path}")
    return 0


def _per_leg_classes(mech, data: dict) -> None:
    """Replace the general elimination's ``singularity`` and ``condition`` of an
    actuated map by those of ``mech``'s per-leg analysis at each assembled grid point
    (its tree configuration read per leg, :meth:`Mechanism.analyze`), and add its
    ``type_I`` and ``type_II`` indices (nan where it does not assemble); the
    ``forward`` and ``inverse`` indices stay the general elimination's, which are its
    own too (:attr:`Analysis.motion_indices`, docs/indices.md)."""
    ok = np.asarray(data["converged"], bool)
    cls = np.asarray(data["singularity"]).astype(object)
    extra = {k: np.full(ok.shape, np.nan) for k in ("condition", "type_I", "type_II")}
    for idx in zip(*np.nonzero(ok)):
        an = mech.analyze(data["q"][idx])
        cls[idx] = an.singularity
        extra["condition"][idx] = an.indices["condition_A"]
        extra["type_I"][idx], extra["type_II"][idx] = (an.indices["type_I"],
                                                       an.indices["type_II"])
    data["singularity"] = cls.astype(str)
    data.update(extra)


def _unit(link, k: int) -> str:
    joint = link.model.tree.joints[link.model.tree.getJointId(link.actuated[k])]
    return "m" if link.model.translating[joint.idx_v] else "rad"


def _slug(spec: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", Path(spec).stem).strip("_") or "mechanism"


def cmd_view(args) -> int:
    """Browser preview of the mechanism at a pose (default: home), a partial pose
    (``--at``, completed on the mechanism's motion and printed) or actuated values
    (``--q``): a self-contained HTML page written to --html, or opened in the browser."""
    from .view import view

    if args.html is not None and not Path(args.html).parent.is_dir():
        raise InputError(f"--html {args.html}: the folder {Path(args.html).parent} does not exist")
    mech = _load(args)
    if args.html is not None and Path(args.html).is_dir():  # a folder: the page inside it
        args.html = str(Path(args.html) / f"{_slug(args.mechanism)}.html")
    where = _open_or_assembled(args, mech)
    pose = _platform_pose(args)
    if isinstance(pose, dict) and not isinstance(where, Exception):  # completed pose
        print(f"given      {', '.join(f'{k}={v:g}' for k, v in pose.items())}")
        print(f"pose       {_pose_text(where.output_pose)}")
    scene = view(mech, where, html=args.html, open=args.html is None or args.open,
                 show_screws=not args.no_screws, show_wrenches=not args.no_wrenches,
                 source=args.mechanism)
    if args.html is not None:
        print(f"wrote      {args.html}")
    else:
        print(f"opened     {mech.name} in the browser")
    if scene.animated:
        print("animated   the uncontrolled motion of this singular pose")
    for name, why in getattr(scene, "failed_sections", {}).items():
        print(f"failed     {name}: {why}; the rest is drawn")
    for k, (sub, a) in enumerate(getattr(scene, "submechanisms", ())):
        print(f"sub [{k}]    {sub.name}: output {sub.output}, DOF {a.dof}, idle DOF "
              f"{a.idle_dof}, output motion {a.motion_type}, singularity {a.singularity}")
    for motion in getattr(scene, "idle_motions", ()):
        print(f"idle       {motion}")
    if getattr(scene, "error", None) is not None:
        print(f"open       drawn at the best configuration reached: {scene.error}")
    return 0


def _open_or_assembled(args, mech):
    """:func:`_assembly`, or the :class:`LoopClosureError` of a linkage that does not
    assemble when it carries the best configuration reached (``view`` draws it open,
    with its gaps)."""
    from .linkage import LoopClosureError

    try:
        return _assembly(args, mech)
    except LoopClosureError as e:
        if e.q is None:
            raise
        return e


def cmd_dynamics(args) -> int:
    """Efforts, speeds and powers of each actuator along a motion
    (:func:`pkm_pin.trajectory.study`): the CSV of ``--trajectory`` (header
    ``t,<actuated names>`` or ``t`` and output coordinates, clamped cubic spline) or
    the default sine about home over ``--duration``; per actuator peak and RMS effort,
    peak speed, peak power and energy as a table or ``--json``; ``--out PREFIX``:
    PREFIX.npz and the PNG plots."""
    from . import trajectory as tr

    if args.trajectory is not None and args.duration is not None:
        raise InputError("--duration is the default motion's; a --trajectory CSV gives its "
                         "own times")
    if not 2 <= args.samples <= 100_000:
        raise InputError(f"--samples must be between 2 and 100000, got {args.samples}")
    prefix = None
    if args.out is not None:
        prefix = Path(args.out)
        if not prefix.parent.is_dir():
            raise InputError(f"--out {prefix}: the folder {prefix.parent} does not exist")
    mech = _load(args)
    if args.indices:
        return _print_dynamic_indices(mech, args)
    if args.sub is not None:
        raise InputError("--sub K goes with --indices (the dynamic indices of one "
                         "independent sub-mechanism); a study moves the whole mechanism")
    motion = None
    if args.trajectory is not None:
        model, _ = tr.closure_model_of(mech)
        motion = tr.read_csv(args.trajectory, model.actuated)
    st = tr.study(mech, motion, samples=args.samples, payload=args.payload,
                  duration=tr.DEFAULT_DURATION if args.duration is None else args.duration)
    files = [] if prefix is None else _study_files(mech, st, prefix)
    replayed = _replay(mech, st) if args.simulate else None
    if args.json:
        print(_json({"mechanism": mech.name, "actuated": list(st.actuated),
                     **({} if replayed is None else {"simulation": replayed}),
                     "motion": st.motion, "samples": int(st.t.size),
                     "duration": float(st.t[-1] - st.t[0]), "gravity": st.gravity.tolist(),
                     "payload": None if st.payload is None else st.payload.tolist(),
                     "notes": list(st.notes), "massless_bodies": list(st.massless_bodies),
                     "actuators": st.summary(), "timing": st.timing,
                     "files": [str(f) for f in files]}))
        return 0
    _print_study(mech, st, replayed, files)
    return 0


def _study_files(mech, st, prefix: Path) -> list:
    """``dynamics --out PREFIX``: PREFIX.npz (the study's arrays) and its PNG plots."""
    from .plots import trajectory_plots

    files = [_save_npz(prefix, dict(
        t=st.t, q=st.q, v=st.v, a=st.a, efforts=st.efforts, q_actuated=st.q_actuated,
        speeds=st.speeds, accelerations=st.accelerations, powers=st.powers,
        payload_efforts=st.payload_efforts, actuated=np.array(st.actuated),
        units=np.array(st.units), gravity=st.gravity))]
    try:
        return files + trajectory_plots(st, prefix, title=mech.name)
    except OSError as e:
        raise InputError(f"cannot write under {prefix}: {e.strerror or e}") from e


def _print_study(mech, st, replayed: dict | None, files: list) -> None:
    """The text report of ``dynamics``: the motion, one line per actuator, the replay."""
    print(f"mechanism  {mech.name}")
    print(f"motion     {st.motion}")
    g = ", ".join(f"{x:g}" for x in st.gravity)
    load = "none" if st.payload is None else (
        "f (" + ", ".join(f"{x:g}" for x in st.payload[:3]) + ") N, m ("
        + ", ".join(f"{x:g}" for x in st.payload[3:]) + ") N m at the output origin")
    print(f"samples    {st.t.size} over [{st.t[0]:g}, {st.t[-1]:g}] s; gravity ({g}) m/s²; "
          f"payload {load}")
    for note in st.notes:
        print(f"note       {note}")
    if st.massless_bodies and not st.notes:
        shown = ", ".join(st.massless_bodies[:6]) + (
            f" and {len(st.massless_bodies) - 6} more" if len(st.massless_bodies) > 6 else "")
        print(f"massless   {len(st.massless_bodies)} bodies have no mass in the file (taken "
              f"massless, none invented): {shown}")
    width = max(8, *(len(n) for n in st.actuated))
    print(f"{'actuator':<{width}}  {'peak effort':>13}  {'rms effort':>13}  "
          f"{'peak speed':>15}  {'peak power':>12}  {'∫|P|dt':>11}  {'∫P dt':>11}")
    for name, s in st.summary().items():
        print(f"{name:<{width}}  {s['peak_effort']:>9.4g} {s['effort_unit']:<3}  "
              f"{s['rms_effort']:>9.4g} {s['effort_unit']:<3}  "
              f"{s['peak_speed']:>9.4g} {s['speed_unit']:<5}  {s['peak_power']:>10.4g} W  "
              f"{s['energy']:>9.4g} J  {s['net_energy']:>9.4g} J")
    if replayed is not None:
        print(f"simulated  forward dynamics ({replayed['method']}, RK4, dt "
              f"{1e3 * replayed['dt']:.3g} ms) of these efforts + PD "
              f"{replayed['bandwidth']:g} Hz: tracking error "
              + ", ".join(f"{x:.3g}" for x in replayed["tracking_error"])
              + f"; closure drift {replayed['max_drift']:.3g}; energy balance "
              f"{replayed['energy_error']:.3g}")
    tm = st.timing
    print(f"time       {tm['total']:.3g} s; per sample {1e3 * tm['kinematics']:.3g} ms position "
          f"kinematics, {1e3 * tm['motion']:.3g} ms v and a, {1e3 * tm['dynamics']:.3g} ms "
          "inverse dynamics")
    for path in files:
        print(f"wrote      {path}")


def _replay(mech, st) -> dict:
    """``dynamics --simulate``: :func:`pkm_pin.simulation.replay` of the study."""
    from . import simulation
    from . import trajectory as tr

    model, _ = tr.closure_model_of(mech)
    r = simulation.replay(model, st.t, st.q[0], st.v[0], st.q_actuated, st.speeds,
                          st.efforts, gravity=st.gravity, payload=st.payload)
    s = r.simulation
    return {"method": s.method, "dt": float(s.t[1] - s.t[0]), "bandwidth": r.bandwidth,
            "tracking_error": r.tracking_error.tolist(), "max_drift": s.max_drift,
            "energy_error": s.energy_error}


def _print_dynamic_indices(mech, args) -> int:
    """``dynamics --indices``: :func:`pkm_pin.dynamic_indices.dynamic_indices` and the
    gravity efforts at home; for a linkage of several independent sub-mechanisms (a
    biped's legs, :mod:`pkm_pin.submechanisms`) those of each one, with its own actuators
    and output (JSON: ``submechanisms``, a list), and with ``--sub K`` those of K alone."""
    subs = _submechanisms_or_why(mech, args.sub)
    parts = subs if args.sub is None else [_pick_sub(mech, subs, args.sub)]
    rows = [(part, *_indices_of(part)) for part in parts]
    if len(rows) > 1:
        data = {"mechanism": mech.name, "submechanisms": [
            {"index": k, "mechanism": p.name, **r.summary(), "gravity_efforts": t.tolist()}
            for k, (p, r, t) in enumerate(rows)]}
        print(_json(data) if args.json else "\n".join(
            [f"mechanism  {mech.name}: {len(rows)} independent sub-mechanisms, each with "
             "its own actuators and output (--sub K: one)"]
            + [line for k, (p, r, t) in enumerate(rows)
               for line in [f"sub {k}      {p.name}"] + _indices_lines(p, r, t)]))
        return 0
    part, r, tau = rows[0]
    if args.json:
        print(_json({"mechanism": part.name, **r.summary(), "gravity_efforts": tau.tolist()}))
        return 0
    print("\n".join(_indices_lines(part, r, tau)))
    return 0


def _indices_of(mech) -> tuple:
    """``(indices, gravity efforts)`` of ``mech`` at home (``dynamics --indices``)."""
    from . import dynamic_indices as di
    from . import trajectory as tr

    model, q = tr.closure_model_of(mech)
    if not any(inertia.mass > 0 for inertia in model.tree.inertias):
        raise InputError(f"{mech.name}: no body has a mass in the file; the dynamic indices "
                         "need the file's inertias")
    return di.dynamic_indices(model, q), di.gravity_efforts(model, q[None]).efforts[0]


def _indices_lines(mech, r, tau) -> list[str]:
    """The text of ``dynamics --indices`` for one mechanism."""
    unit = {"rad": "N m", "m": "N"}
    lines = [f"mechanism  {mech.name} (at home; docs/dynamics.md)"]
    lines += [f"actuator   {name} [{u}]: Λ row " + " ".join(f"{x:.4g}" for x in row)
              + f"; gravity effort {t:.4g} {unit[u]}"
              for name, u, row, t in zip(r.actuated, r.units, r.inertia, tau)]
    lines.append("eigen      Λ̃ = Uₐ Λ Uₐ [kg m²]: " + " ".join(f"{x:.4g}" for x in r.eigenvalues)
                 + f"; condition {r.condition:.4g}; idle motions {r.idle_motions}")
    X = r.output_inertia  # round-off of a rank-deficient Λ_x printed as 0
    X = np.where(np.abs(X) <= 1e-12 * max(np.abs(X).max(initial=0.0), 1e-300), 0.0, X)
    lines.append("output     Λ_x about the output origin, world axes, rows and columns (ω; v):")
    lines += ["           " + " ".join(f"{x + 0.0:>10.4g}" for x in row) for row in X]
    return lines


def cmd_workspace(args) -> int:
    """Reachable, singularity-free and good-transmission workspaces
    (:func:`pkm_pin.workspace.workspace`): print (or ``--json``) the volumes with their
    errors, the inscribed shapes and the counts; write PREFIX.json, PREFIX.npz, the PNG
    pictures and PREFIX.html or ``--view FILE.html`` (a meshcat point cloud, with each
    kind's boundary surface for three coordinates)."""
    from .checkpoint import Checkpoint, atomic_savez, atomic_write, graceful_stop
    from .plots import workspace_plots
    from .view import workspace_cloud

    prefix = _out_prefix(args, f"workspace_{_slug(args.mechanism)}")
    mech, note = _workspace_part(args, _load(args))
    coords = args.coords
    if args.range is not None and coords is None:
        raise InputError("--range needs --coords (the coordinates it bounds)")
    if args.range is not None and len(args.range) != 2 * len(coords):
        raise InputError(f"--range takes {2 * len(coords)} bounds (lo hi per coordinate), "
                         f"got {len(args.range)}")
    bounds = None if args.range is None else np.reshape(args.range, (-1, 2))
    options = dict(bounds=bounds, n=args.n, kinds=args.kind, progress=not args.quiet)
    if args.sobol is not None:
        options.update(sampling="sobol", samples=args.sobol)
    if args.at:
        options.update(at=at_values(args.at))
    options.update(chunk_size=args.chunk_size, checkpoint=Checkpoint(
        prefix, resume=args.resume is not None, keep=True,
        identity=_mechanism_identity(args)))
    executor = None
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        executor = ProcessPoolExecutor(args.jobs)
        options.update(executor=executor)
    try:
        with graceful_stop(_stopping):
            ws = mech.workspace(coords, **options)
    except KeyboardInterrupt as e:
        _attach(e, options.get("checkpoint"))
        raise
    finally:
        if executor is not None:
            executor.shutdown(cancel_futures=True)
    data = ws.as_dict()
    files = [prefix.with_name(prefix.name + ".json"), prefix.with_name(prefix.name + ".npz")]
    try:  # written under temporary names, then renamed: never a truncated file
        atomic_write(files[0], lambda tmp: Path(tmp).write_text(_json(data)))
        atomic_savez(files[1], compressed=True, points=ws.points, shape=np.array(ws.shape),
                            coords=np.array(ws.coords), bounds=ws.bounds,
                            **{f"mask_{k}": m for k, m in ws.masks.items()},
                            **{k: v for k, v in ws.values.items()},
                            **{f"axis_{i}": a for i, a in enumerate(ws.axes)})
        files += workspace_plots(ws, prefix, title=mech.name)
        html = Path(args.view) if args.view else prefix.with_name(prefix.name + ".html")
        workspace_cloud(ws, html=html)
        files.append(html)
    except OSError as e:
        raise InputError(f"cannot write under {prefix}: {e.strerror or e}") from e
    if options.get("checkpoint") is not None:  # the outputs are written
        options["checkpoint"].remove()
    data["files"] = [str(f) for f in files]
    print(_json(data) if args.json else "\n".join(
        [_workspace_text(mech.name, ws, files)] + ([note] if note else [])))
    return 0


def _workspace_part(args, mech) -> tuple:
    """``(mechanism, note)``: what ``workspace`` studies: with ``--sub K`` a linkage's
    independent sub-mechanism K (its own actuators and output, as ``map --sub K``), else
    the whole, with a note when it has several sub-mechanisms (None otherwise)."""
    subs = _submechanisms_or_why(mech, args.sub)
    if args.sub is not None:
        return _pick_sub(mech, subs, args.sub), None
    if len(subs) <= 1:
        return mech, None
    words = "; ".join(f"{k}: {s.name}, output {s.output}" for k, s in enumerate(subs))
    return mech, (f"note       {len(subs)} independent sub-mechanisms ({words}): this is the "
                  f"workspace of the one output {mech.output!r}, which the others' motors "
                  "do not move (type I at every pose: the singularity-free workspace is "
                  "empty for that reason, not for singular poses); --sub K studies one with "
                  "its own output")


def _workspace_text(name: str, ws, files: list) -> str:
    """The text summary of ``pkm-pin workspace``: box, volumes, inscribed shapes, time
    and the files written."""
    out = [f"mechanism  {name}  ({ws.method})",
           "box        " + ", ".join(f"{c} in [{lo:g}, {hi:g}] {u}" for c, (lo, hi), u in
                                    zip(ws.coords, ws.bounds, ws.units))
           + f"; {ws.sampling} {' x '.join(map(str, ws.shape))}"]
    if ws.fixed:
        out.append("fixed      " + ", ".join(f"{k}={v:g}" for k, v in ws.fixed.items()))
    for kind, v in ws.volumes.items():
        shapes = _inscribed_words(ws.inscribed[kind], len(ws.coords))
        out.append(f"{kind:<18} volume {v.value:.6g} ± {v.error:.2g} {v.unit} ({v.cells} "
                   f"cells){'; ' + shapes if shapes else ''}")
    if ws.counts["on_bounds"]:
        out.append(f"note       {ws.counts['on_bounds']} reachable cells on the box's faces: "
                   "the workspace extends beyond --range")
    out.append(f"time       {ws.timing['total']:.3g} s, {ws.timing['poses_per_s']:.0f} poses/s")
    out += [f"wrote      {path}" for path in files]
    return "\n".join(out)


def _inscribed_words(s, k: int) -> str:
    """The inscribed shapes of a workspace summary in words, by the number ``k`` of
    coordinates (a cube, square or half length; a cylinder or disc), each left out where
    it is not defined (coordinates of different units: nan); sizes below a billionth of
    the resolution are 0 (rounding)."""
    def size(x: float) -> str:
        return f"{0.0 if abs(x) <= 1e-9 * s.error else x:.4g}"

    parts = []
    if np.isfinite(s.cube):
        name = {3: "cube half side", 2: "square half side"}.get(k, "half length")
        parts.append(f"{name} {size(s.cube)}")
    if k == 3 and np.isfinite(s.cylinder_radius) and np.isfinite(s.cylinder_half_height):
        parts.append(f"cylinder r {size(s.cylinder_radius)} h/2 "
                     f"{size(s.cylinder_half_height)}")
    elif k == 2 and np.isfinite(s.cylinder_radius):
        parts.append(f"disc r {size(s.cylinder_radius)}")
    if not parts:
        return ""
    return ", ".join(parts) + f" (± {s.error:.2g})"


def _write_text(path: str, text: str) -> None:
    try:
        Path(path).write_text(text)
    except OSError as e:
        raise InputError(f"cannot write {path}: {e.strerror or e}") from e


# --------------------------------------------------------------------- parser
#: A negative number as a command-line word, scientific notation included (``-7e-17``,
#: ``-1.5E+3``, ``-.5``): argparse's own rule (``-12``, ``-1.5`` only, before Python
#: 3.13) reads ``-7e-17`` as an option, so a value printed by ``fk --json`` and pasted
#: into ``--q``, ``--pose``, ``--range`` or ``--payload`` was refused.
NEGATIVE_NUMBER = re.compile(r"^-(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?$")


class _Parser(argparse.ArgumentParser):
    """``argparse`` parser whose usage errors are one line on stderr, status 2, and whose
    negative numbers (never options: none of ours looks like one) include scientific
    notation (:data:`NEGATIVE_NUMBER`; the sub-commands' parsers are of this class too)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str):  # noqa: D102
        self.exit(2, f"pkm-pin: error: {message} (see '{self.prog} --help')\n")


def _pose_option(p, default: str = "the home pose") -> None:
    p.add_argument("--pose", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                   help=f"platform (linkage: output) pose: x, y, z [m], roll, pitch, yaw [rad] "
                   f"(default: {default})")


def _at_option(p, text: str = "") -> None:
    p.add_argument("--at", nargs="+", metavar="NAME=VALUE",
                   help=text or "a partial pose: some of x, y, z [m], roll, pitch, yaw [rad] "
                   "that are independent coordinates of the mechanism (e.g. z=0.8 roll=0.1 "
                   "pitch=0 for a 3-RPS); the others are solved for (a linkage without "
                   "legs: its output frame's coordinates given, the others free)")


def _linkage_options(p, q: bool = False) -> None:
    """``--output``, ``--point`` / ``--body``, ``--closures`` (and ``--q``) of a linkage."""
    g = p.add_argument_group("general linkages (.urdf, .xml, .mjcf, pinned .toml)")
    g.add_argument("--output", metavar="FRAME",
                   help="frame whose motion is analysed (default: the file's output)")
    how = g.add_mutually_exclusive_group()
    how.add_argument("--point", dest="point", action="store_const", const=True,
                     help="analyse the output frame's origin as a point")
    how.add_argument("--body", dest="point", action="store_const", const=False,
                     help="analyse the output frame as a body")
    g.add_argument("--closures", metavar="FILE",
                   help="closures file (.yaml / .toml) of a .urdf (default: found beside it); "
                   "'none': the URDF's tree without closures, every movable joint actuated "
                   "(a serial arm)")
    g.add_argument("--backend", choices=("legs", "general"),
                   help="legs: the per-leg screw engine, also for a .urdf/.xml in which a "
                   "base-legs-platform machine is detected (same numbers as TOML legs); "
                   "general: the general elimination for any file (default: by file)")
    if q:
        g.add_argument("--q", nargs="+", type=float, metavar="Q",
                       help="actuated values [rad or m]: forward kinematics first (also for "
                       "platform mechanisms)")


_MECH_HELP = ("mechanism file (.toml, or a linkage: .urdf, .xml, .mjcf) or shipped model "
              "name (see 'pkm-pin list')")


def build_parser() -> argparse.ArgumentParser:
    """The ``pkm-pin`` argument parser (every sub-command has ``--help``)."""
    parser = _Parser(prog="pkm-pin",
                     description="Screw-theory analysis of parallel kinematic machines "
                     "and closed-loop linkages (Pinocchio). MECHANISM is a .toml file, a "
                     ".urdf (with its closures file) or .xml / .mjcf linkage, or a shipped "
                     "model name.")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("list", help="shipped models with one-line descriptions",
                       description="List the shipped models "
                       "(builders and models/mechanisms/*.toml).")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_list)

    p = sub.add_parser("analyze", help="mobility, Jacobians and singularity of one pose",
                       description="Analyse a mechanism at a pose (default: its home pose). "
                       "With no MECHANISM: the built-in 3-RPR of seed 000.")
    p.add_argument("mechanism", nargs="?", metavar="MECHANISM", help=_MECH_HELP)
    _pose_option(p)
    _at_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--markdown", metavar="FILE", help="also write a Markdown report to FILE")
    p.add_argument("--plots", nargs="+", metavar="PNG",
                   help="image files to link in the report (e.g. from 'pkm-pin map')")
    _linkage_options(p, q=True)
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("check", help="validate a mechanism file and its URDFs",
                       description="Load a mechanism file (and its URDFs), assemble it at home "
                       "and analyse it; say what is wrong. Exit status 0: fine, 1: warnings, "
                       "2: error.")
    p.add_argument("file", metavar="FILE", help="mechanism file (.toml, .urdf, .xml, .mjcf)")
    _linkage_options(p)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("fk", help="forward kinematics: actuated coordinates -> pose",
                       description="Platform pose for the actuated coordinates (continuation "
                       "from home); with --all every assembly mode found.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("q", nargs="*", type=float, metavar="Q",
                   help="actuated coordinates [m or rad], in the order of 'analyze' (none "
                   "for a linkage without actuators: its assembly from the reference)")
    p.add_argument("--all", action="store_true", help="every assembly mode found")
    p.add_argument("--starts", type=int, default=32, help="start assemblies of --all (32)")
    p.add_argument("--seed", type=int, default=0, help="random seed of --all (0)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--sub", type=int, metavar="K",
                   help="linkage with independent sub-mechanisms (a biped's legs, listed "
                   "by 'analyze' and 'check'): Q are the actuated values of sub-mechanism "
                   "K alone, the others held at the reference assembly")
    _linkage_options(p)
    p.set_defaults(func=cmd_fk)

    p = sub.add_parser("ik", help="inverse kinematics: pose -> actuated coordinates",
                       description="Actuated coordinates at a pose (legs on the working mode "
                       "of home); with --all every working mode.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    _pose_option(p)
    _at_option(p)
    p.add_argument("--all", action="store_true", help="every working mode")
    p.add_argument("--json", action="store_true", help="print JSON")
    _linkage_options(p)
    p.set_defaults(func=cmd_ik)

    p = sub.add_parser("sensitivity", help="output error per unit geometric error",
                       description="How far the output moves, actuated joints held, per unit "
                       "error of each geometric parameter (joint origins and axes, leg bases "
                       "and anchors, closure frames), largest first; the errors the rigid "
                       "mechanism cannot absorb are listed apart.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("--parameters", nargs="+", metavar="NAME",
                   help="names, a joint's or leg's name, or globs ('*/origin.z'); default all")
    p.add_argument("--top", type=int, default=15, help="rows printed (15)")
    p.add_argument("--json", action="store_true", help="print one JSON object (every parameter)")
    _linkage_options(p, q=True)
    p.set_defaults(func=cmd_sensitivity)

    p = sub.add_parser("map", help="singularity and conditioning maps of a workspace slice",
                       description="Sweep two pose coordinates (--axes, or --plane), the "
                       "others given by --at, held at home as the mechanism's DOF needs, the "
                       "rest (parasitic motions) solved for; write PREFIX.npz (every array), "
                       "PREFIX_singularity.png and PREFIX_conditioning.png.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("--plane", choices=sorted(PLANES),
                   help="the two varied coordinates (default xy; platform mechanisms)")
    p.add_argument("--axes", nargs=2, metavar="NAME",
                   help="any two independent coordinates of x y z roll pitch yaw (e.g. roll "
                   "pitch; platform mechanisms)")
    _at_option(p, "values of other independent coordinates, e.g. z=0.8 (default: home)")
    p.add_argument("--range", nargs="+", type=float, metavar="BOUND",
                   help="A B C D: first coordinate from A to B, second from C to D "
                   "(default: home ± the characteristic length, angles ± 0.5 rad; for a "
                   "linkage: the joint "
                   "limits of the varied actuated joints, or ± π rad)")
    p.add_argument("--n", type=int, default=50, help="grid points per coordinate (default 50)")
    p.add_argument("--fixed", nargs="+", metavar="NAME=VALUE",
                   help="as --at (x y z roll pitch yaw; default home; "
                   "for a linkage: the other actuated joints, default their reference values)")
    p.add_argument("--actuated", nargs="+", metavar="NAME",
                   help="map over these one or two actuated joints (a linkage's default: its "
                   "first two; a platform mechanism is then read through its legs-and-platform "
                   "tree)")
    p.add_argument("--sub", type=int, metavar="K",
                   help="linkage with independent sub-mechanisms (a biped's legs, listed by "
                   "'check'): map sub-mechanism K alone, with its own output, the others "
                   "held at the reference assembly")
    p.add_argument("--out", metavar="PREFIX", help="output prefix (default map_NAME_PLANE); "
                   "the results so far are kept in PREFIX.partial.npz while it runs")
    p.add_argument("--resume", metavar="PREFIX",
                   help="continue the interrupted map of PREFIX.partial.npz (same command "
                   "and options)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--chunk-size", type=int, default=500, help="poses per worker task (500)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _linkage_options(p)
    p.set_defaults(func=cmd_map)

    p = sub.add_parser("workspace", help="reachable / singularity-free / transmission "
                       "workspaces, volumes, inscribed cube and cylinder",
                       description="Sample the workspace over some pose coordinates (default "
                       "the independent ones; a linkage: its output point, or actuated joints) "
                       "on a grid; write PREFIX.json (volumes with errors, inscribed shapes, "
                       "counts), PREFIX.npz, PNG pictures and PREFIX.html (meshcat point "
                       "cloud; with three coordinates, each workspace's boundary surface).")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("--coords", nargs="+", metavar="NAME",
                   help="1 to 3 of x y z roll pitch yaw (a linkage: x y z of its output "
                   "point, or actuated joint names)")
    p.add_argument("--range", nargs="+", type=float, metavar="BOUND",
                   help="lo hi per coordinate (default home ± the characteristic length, "
                   "angles ± 0.5 rad)")
    p.add_argument("--n", type=int, default=30, help="grid cells per coordinate (30)")
    p.add_argument("--sobol", type=int, metavar="N",
                   help="N seeded quasi-random samples instead of a grid")
    p.add_argument("--kind", nargs="+", choices=("reachable", "singularity-free",
                                                 "transmission"),
                   help="the workspaces computed (default all available)")
    _at_option(p, "values of other pose coordinates (default: home)")
    p.add_argument("--out", metavar="PREFIX", help="output prefix (default workspace_NAME); "
                   "the results so far are kept in PREFIX.partial.npz while it runs")
    p.add_argument("--resume", metavar="PREFIX",
                   help="continue the interrupted study of PREFIX.partial.npz (same command "
                   "and options)")
    p.add_argument("--json", action="store_true", help="print the JSON numbers")
    p.add_argument("--view", metavar="FILE.html",
                   help="write the browser view there (default PREFIX.html): point cloud "
                   "and, for three coordinates, each workspace's boundary surface")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--chunk-size", type=int, default=2000, help="poses per task (2000)")
    p.add_argument("--sub", type=int, metavar="K",
                   help="independent sub-mechanism K of a linkage alone (a biped's leg K, "
                   "numbered from 0), with its own actuators and output")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    _linkage_options(p)
    p.set_defaults(func=cmd_workspace)

    p = sub.add_parser("view", help="browser preview (meshcat)",
                       description="Draw the mechanism at a pose (legs, platform, joint screws, "
                       "actuation and constraint wrenches) in a meshcat scene: write it as a "
                       "self-contained HTML page, or open it in the browser.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    _pose_option(p)
    _at_option(p)
    p.add_argument("--html", metavar="FILE", help="write the page to FILE (no browser)")
    p.add_argument("--open", action="store_true", help="with --html: open it too")
    p.add_argument("--no-screws", action="store_true", help="do not draw the joint screws")
    p.add_argument("--no-wrenches", action="store_true", help="do not draw the wrenches")
    _linkage_options(p, q=True)
    p.set_defaults(func=cmd_view)

    p = sub.add_parser("dynamics", help="actuator efforts, speeds and powers along a motion",
                       description="Closed-loop inverse dynamics along a motion of the "
                       "actuators (docs/dynamics.md): the consistent motion of every joint, "
                       "then per actuator peak and RMS effort, peak speed, peak power and "
                       "energy (the file's inertias only: a model with no mass anywhere is "
                       "refused unless a payload is given). With no MECHANISM: the built-in "
                       "3-RPR; with no --trajectory: each actuator a sine about home.")
    p.add_argument("mechanism", nargs="?", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("--trajectory", metavar="CSV",
                   help="the motion: a CSV with the header t,<actuated names> (any order) "
                   "or t and some of x,y,z,roll,pitch,yaw (the output's coordinates, the "
                   "others held by the mechanism) and one row per sample [s, rad or m], "
                   "splined (cubic, at rest at both ends)")
    p.add_argument("--duration", type=float, metavar="T",
                   help="duration of the default motion [s] (default 2)")
    p.add_argument("--samples", type=int, default=201,
                   help="samples, uniform in time (default 201)")
    p.add_argument("--payload", nargs=6, type=float,
                   metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
                   help="wrench on the output at its origin, world axes [N, N m] (a mass m: "
                   "0 0 -9.81m 0 0 0)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", metavar="PREFIX",
                   help="write PREFIX.npz (t, q, v, a, efforts, ...) and PREFIX_efforts.png, "
                   "_speeds.png, _powers.png, _torque_speed.png")
    p.add_argument("--simulate", action="store_true",
                   help="then simulate the forward dynamics of these efforts (plus a PD on "
                   "the actuators) and print the tracking error, closure drift and energy "
                   "balance")
    p.add_argument("--indices", action="store_true",
                   help="print the dynamic indices at home instead: actuator-space inertia "
                   "Gᵀ M G, its eigenvalues and condition, the apparent inertia at the "
                   "output, the gravity efforts")
    p.add_argument("--sub", type=int, metavar="K",
                   help="with --indices: independent sub-mechanism K of a linkage alone "
                   "(a biped's leg K, numbered from 0); without it each one's")
    _linkage_options(p)
    p.set_defaults(func=cmd_dynamics)
    return parser


def resume_command(argv, error) -> str:
    """The command that continues an interrupted study: this one with ``--out PREFIX``
    replaced by ``--resume PREFIX``."""
    import shlex

    prefix = str(error.checkpoint.prefix) if error.checkpoint is not None else None
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
            continue
        if a in ("--out", "--resume"):
            skip = True
            continue
        if a.startswith(("--out=", "--resume=")):
            continue
        out.append(a)
    return shlex.join(["pkm-pin", *out, "--resume", prefix or "PREFIX"])


def _error_line(error: PkmError, args) -> str:
    """The message of ``error`` on one line, prefixed with the mechanism file when it
    does not name it (an analysis error such as "loop ... does not close" comes from a
    file the user should see named, most of all when many files are analysed)."""
    message = str(error)
    spec = getattr(args, "mechanism", None)
    if isinstance(spec, str) and _is_file(Path(spec)) and Path(spec).name not in message:
        message = f"{_clip(spec)}: {message}"
    return " ".join(message.split())  # every line break (also U+2028, U+0085) a space


def _fk_values_after_options(extras: list) -> tuple[list, list]:
    """``fk``'s Q (which may be empty: a linkage without actuators) given after an option
    (``fk FILE --sub 1 Q…``): argparse has matched the empty Q before the option, so the
    values come back unrecognized; ``(values, [])``, or ``([], extras)`` when one is not
    a number."""
    try:
        return [float(x) for x in extras], []
    except ValueError:
        return [], extras


def main(argv=None) -> int:
    """Entry point of ``pkm-pin``; returns the exit status."""
    parser = build_parser()
    try:
        args, extras = parser.parse_known_args(argv)
        if extras and args.command == "fk":  # after an option, or a value such as
            values, extras = _fk_values_after_options(extras)  # -7e-17 (argparse: an option)
            args.q = list(args.q or []) + values
        if extras:
            parser.error(f"unrecognized arguments: {' '.join(extras)}")
    except SystemExit as e:  # --help (0) or a usage error (2), already printed
        return int(e.code or 0)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    from .checkpoint import Interrupted, interrupt_line

    try:
        return args.func(args)
    except Interrupted as e:  # the chunks done are saved: say how to continue
        print(interrupt_line(e, resume_command(args.argv, e)), file=sys.stderr)
        return e.exit_status
    except PkmError as e:
        print(f"pkm-pin: error: {_error_line(e, args)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("pkm-pin: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into a command that stopped reading (head)
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        except (OSError, ValueError):
            pass
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
