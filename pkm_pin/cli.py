"""Command-line interface ``pkm-pin``: one entry point, one sub-command per task.

::

    pkm-pin list                                   shipped models, one line each
    pkm-pin analyze [MECHANISM] [--pose X Y Z R P Y] [--json] [--markdown FILE]
    pkm-pin check FILE                             validate a mechanism file and its URDFs
    pkm-pin fk MECHANISM Q... [--all]              actuated coordinates -> platform pose(s)
    pkm-pin ik MECHANISM [--pose X Y Z R P Y] [--all]   pose -> actuated coordinates
    pkm-pin map MECHANISM --plane xz --range A B C D --n 100 --out PREFIX
    pkm-pin view MECHANISM [--pose ...] [--html FILE]   browser preview (meshcat)

``MECHANISM`` is a mechanism file (``.toml``) or the name of a shipped model
(``pkm-pin list``). Poses are x, y, z [m] and URDF roll, pitch, yaw [rad].

User mistakes print one line ``pkm-pin: error: …`` on stderr and exit with status 2; no
Python traceback. ``check`` exits with 1 when the file loads but has warnings.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from pathlib import Path

import numpy as np

from .errors import InputError, PkmError
from .tolerances import CROSSCHECK_TOL

#: Pose coordinates in the order of ``--pose`` and of the sweep arrays.
POSE_NAMES = ("x", "y", "z", "roll", "pitch", "yaw")
#: Varied coordinates of each ``map --plane``.
PLANES = {"xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


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
    from .mechanism import tomllib

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


def load(spec: str | None):
    """The mechanism named by ``spec``: a file path, a shipped model name, or ``None``
    (the 3-RPR of seed 000, Michalková & Guldan, see docs/references.md).

    Raises:
        MechanismFileError: the file is missing or wrong.
        InputError: ``spec`` is neither a file nor a shipped model.
    """
    from .builders import MECHANISMS
    from .mechanism import load_mechanism

    if spec is None:
        return MECHANISMS["rpr3"]().build()
    path = Path(spec)
    if _is_file(path) or spec.endswith(".toml") or "/" in spec or "\\" in spec:
        return load_mechanism(path)
    if spec in MECHANISMS:
        return MECHANISMS[spec]().build()
    shipped = models_dir() / f"{spec}.toml"
    if _is_file(shipped):
        return load_mechanism(shipped)
    shown = spec if len(spec) <= 80 else spec[:77] + "..."
    raise InputError(f"{shown!r} is neither a mechanism file nor a shipped model; the shipped "
                     f"models are: {', '.join(sorted(shipped_models()))} (see 'pkm-pin list')")


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False for names the OS refuses (too long, NUL byte)."""
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


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
        print(json.dumps(models, indent=2))
        return 0
    width = max(len(n) for n in models)
    for name, m in sorted(models.items()):
        print(f"{name:<{width}}  {m['description']}")
    return 0


def cmd_analyze(args) -> int:
    """Report of one pose (default: home) as text or JSON, optionally as Markdown."""
    from . import report

    mech = load(args.mechanism)
    analysis = mech.analyze(None if args.pose is None else args.pose)
    data = report.report_data(analysis, plots=args.plots or ())
    if args.markdown:
        _write_text(args.markdown, report.markdown(analysis, data=data))
    if args.json:
        print(json.dumps(data, indent=2, default=float))
    else:
        print(report.text(data))
        if args.markdown:
            print(f"markdown           {args.markdown}")
    return 0


def cmd_check(args) -> int:
    """Load a mechanism file, assemble it at home and analyse it; report problems."""
    from .crosscheck import crosscheck
    from .mechanism import load_mechanism

    path = Path(args.file)
    if not _is_file(path) and _is_file(models_dir() / f"{args.file}.toml"):
        path = models_dir() / f"{args.file}.toml"
    mech = load_mechanism(path)
    print(f"ok    loads: {mech.name!r}, {len(mech.legs)} legs "
          f"({', '.join(f'{leg.name}: {leg.nv} joints' for leg in mech.legs)}), "
          f"{mech.n_actuated} actuated ({', '.join(mech.actuated_names)})")
    asm = mech.home_assembly
    print(f"ok    assembles at home {_pose_text(asm.pose)} (closure residual {asm.residual:.2g})")
    an = mech.analyze(asm)
    print(f"ok    analysis: DOF {an.dof} ({an.motion_type}), Grübler count {an.grubler}, "
          f"redundant constraints {an.redundant_constraints}, singularity {an.singularity}")
    warnings = []
    if an.dof == 0:
        warnings.append("the platform cannot move at home (DOF 0)")
    if mech.n_actuated != an.dof:
        more = "more" if mech.n_actuated > an.dof else "fewer"
        warnings.append(f"{mech.n_actuated} actuated joints for {an.dof} DOF: {more} actuators "
                        "than degrees of freedom")
    if an.singularity != "none":
        warnings.append(f"the home pose is a type {an.singularity} singularity (indices "
                        + ", ".join(f"{k} {v:.2g}" for k, v in an.indices.items()) + ")")
    checks = crosscheck(an)
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


def cmd_fk(args) -> int:
    """Forward kinematics: pose(s) for the actuated coordinates."""
    mech = load(args.mechanism)
    q = mech.check_actuated(args.q)
    if args.all:
        found = mech.forward_kinematics_all(q, starts=args.starts, seed=args.seed)
    else:
        found = [mech.forward_kinematics(q)]
    rows = [{"pose": _pose_dict(a.pose), "q_actuated": a.q_actuated.tolist(),
             "residual": float(a.residual),
             "leg_q": {leg.name: qi.tolist() for leg, qi in zip(mech.legs, a.leg_q)}}
            for a in found]
    if args.json:
        print(json.dumps(rows if args.all else rows[0], indent=2))
        return 0
    print(f"mechanism  {mech.name}")
    print(f"actuated   {', '.join(mech.actuated_names)} = {_fmt(q)}")
    if not found:
        print("no assembly mode found")
    for i, a in enumerate(found):
        label = f"mode {i + 1}" if args.all else "pose"
        print(f"{label:<10} {_pose_text(a.pose)}")
    return 0


def cmd_ik(args) -> int:
    """Inverse kinematics: actuated coordinates at a pose (every working mode with --all)."""
    mech = load(args.mechanism)
    pose = mech.home if args.pose is None else args.pose
    if args.all:
        modes = [a.q_actuated for a in mech.inverse_kinematics_all(pose)]
    else:
        modes = [mech.inverse_kinematics(pose)]
    if args.json:
        body = {"actuated": mech.actuated_names, "q_actuated": [m.tolist() for m in modes]}
        if not args.all:
            body["q_actuated"] = body["q_actuated"][0]
        print(json.dumps(body, indent=2))
        return 0
    from .assembly import as_pose

    print(f"mechanism  {mech.name}")
    print(f"pose       {_pose_text(as_pose(pose))}")
    print(f"actuated   {', '.join(mech.actuated_names)}")
    for i, m in enumerate(modes):
        print(f"{f'mode {i + 1}' if args.all else 'q':<10} {_fmt(m)}")
    return 0


def _fixed_values(items, home: np.ndarray, varied: tuple[int, int]) -> np.ndarray:
    """The pose coordinates held fixed: home, overridden by ``NAME=VALUE`` items."""
    values = home.copy()
    for item in items or ():
        name, _, text = item.partition("=")
        name = name.strip().lower()
        if name not in POSE_NAMES or not text:
            raise InputError(f"--fixed takes NAME=VALUE with NAME in {', '.join(POSE_NAMES)}; "
                             f"got {item!r}")
        k = POSE_NAMES.index(name)
        if k in varied:
            raise InputError(f"--fixed {name}: {name} is varied over the plane")
        try:
            values[k] = float(text)
        except ValueError as e:
            raise InputError(f"--fixed {name}: {text!r} is not a number") from e
        if not np.isfinite(values[k]):
            raise InputError(f"--fixed {name}: the value must be finite, got {text!r}")
    return values


def map_slice(mech, plane: str, ranges, n: int, fixed=()) -> tuple[np.ndarray, np.ndarray,
                                                                     np.ndarray]:
    """Grid of poses over a plane of the pose coordinates.

    Returns:
        ``(u, v, poses)``: coordinates of the columns (n_u,), of the rows (n_v,), and the
        poses (n_v · n_u, 6) in row-major order (row ``j`` at ``v[j]``).
    """
    import pinocchio as pin

    i, j = PLANES[plane]
    home = np.r_[mech.home.translation, pin.rpy.matrixToRpy(mech.home.rotation)]
    base = _fixed_values(fixed, home, (i, j))
    if ranges is None:
        L = mech.characteristic_length
        ranges = [home[i] - L, home[i] + L, home[j] - L, home[j] + L]
    a, b, c, d = (float(x) for x in ranges)
    if not all(np.isfinite([a, b, c, d])) or a == b or c == d:
        raise InputError(f"--range needs finite bounds with A != B and C != D, got {ranges}")
    if not 2 <= n <= 2000:
        raise InputError(f"--n must be between 2 and 2000, got {n}")
    u, v = np.linspace(a, b, n), np.linspace(c, d, n)
    V, U = np.meshgrid(v, u, indexing="ij")
    poses = np.tile(base, (U.size, 1))
    poses[:, i], poses[:, j] = U.ravel(), V.ravel()
    return u, v, poses


def cmd_map(args) -> int:
    """Sweep a workspace slice; write PREFIX.npz and the two PNG maps."""
    from .plots import save_maps

    prefix = Path(args.out if args.out else f"map_{_slug(args.mechanism)}_{args.plane}")
    if not prefix.parent.is_dir():
        raise InputError(f"--out {prefix}: the folder {prefix.parent} does not exist")
    mech = load(args.mechanism)
    u, v, poses = map_slice(mech, args.plane, args.range, args.n, args.fixed)
    i, j = PLANES[args.plane]
    executor = None
    if args.jobs > 1:
        from concurrent.futures import ProcessPoolExecutor

        executor = ProcessPoolExecutor(args.jobs)
    try:
        result = mech.sweep(poses, executor=executor, progress=not args.quiet,
                            chunk_size=args.chunk_size if executor else max(len(poses), 1))
    finally:
        if executor is not None:
            executor.shutdown()
    shape = (v.size, u.size)
    data = {k: a.reshape(shape + a.shape[1:]) for k, a in result.arrays().items()}
    units = ["m"] * 3 + ["rad"] * 3
    data.update(u=u, v=v, plane=np.array(args.plane),
                labels=np.array([f"{POSE_NAMES[i]} [{units[i]}]", f"{POSE_NAMES[j]} [{units[j]}]"]),
                mechanism=np.array(mech.name), actuated=np.array(mech.actuated_names),
                failure_index=np.array([f[0] for f in result.failures], dtype=int),
                failure_reason=np.array([f[1] for f in result.failures], dtype=str))
    npz = prefix.with_name(prefix.name + ".npz")
    try:
        np.savez_compressed(npz, **data)
    except OSError as e:
        raise InputError(f"cannot write {npz}: {e.strerror or e}") from e
    pngs = save_maps(data, prefix, title=mech.name)
    n_ok = int(result.ok.sum())
    counts = {c: int(np.sum(result.singularity == c)) for c in ("I", "II", "III")}
    print(f"mechanism  {mech.name}")
    print(f"slice      {args.plane}: {POSE_NAMES[i]} in [{u[0]:g}, {u[-1]:g}], "
          f"{POSE_NAMES[j]} in [{v[0]:g}, {v[-1]:g}], {u.size} × {v.size} poses")
    print(f"assembled  {n_ok} of {len(poses)}; singular grid points: "
          + ", ".join(f"type {k} {c}" for k, c in counts.items()))
    for path in [npz, *pngs]:
        print(f"wrote      {path}")
    return 0


def _slug(spec: str) -> str:
    return re.sub(r"[^A-Za-z0-9]+", "_", Path(spec).stem).strip("_") or "mechanism"


def cmd_view(args) -> int:
    """Browser preview of the mechanism at a pose (default: home): a self-contained
    HTML page written to --html, or opened in the browser."""
    from .view import view

    if args.html is not None and not Path(args.html).parent.is_dir():
        raise InputError(f"--html {args.html}: the folder {Path(args.html).parent} does not exist")
    mech = load(args.mechanism)
    scene = view(mech, args.pose, html=args.html, open=args.html is None or args.open,
                 show_screws=not args.no_screws, show_wrenches=not args.no_wrenches)
    if args.html is not None:
        print(f"wrote      {args.html}")
    else:
        print(f"opened     {mech.name} in the browser")
    if scene.animated:
        print("animated   the uncontrolled motion of this singular pose")
    return 0


def _write_text(path: str, text: str) -> None:
    try:
        Path(path).write_text(text)
    except OSError as e:
        raise InputError(f"cannot write {path}: {e.strerror or e}") from e


# --------------------------------------------------------------------- parser
class _Parser(argparse.ArgumentParser):
    """``argparse`` parser whose usage errors are one line on stderr, status 2."""

    def error(self, message: str):  # noqa: D102
        self.exit(2, f"pkm-pin: error: {message} (see '{self.prog} --help')\n")


def _pose_option(p, default: str = "the home pose") -> None:
    p.add_argument("--pose", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                   help=f"platform pose: x, y, z [m], roll, pitch, yaw [rad] (default: {default})")


_MECH_HELP = "mechanism file (.toml) or shipped model name (see 'pkm-pin list')"


def build_parser() -> argparse.ArgumentParser:
    """The ``pkm-pin`` argument parser (every sub-command has ``--help``)."""
    parser = _Parser(prog="pkm-pin",
                     description="Screw-theory analysis of parallel kinematic machines "
                     "(Pinocchio). MECHANISM is a .toml file or a shipped model name.")
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
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--markdown", metavar="FILE", help="also write a Markdown report to FILE")
    p.add_argument("--plots", nargs="+", metavar="PNG",
                   help="image files to link in the report (e.g. from 'pkm-pin map')")
    p.set_defaults(func=cmd_analyze)

    p = sub.add_parser("check", help="validate a mechanism file and its URDFs",
                       description="Load a mechanism file (and its URDFs), assemble it at home "
                       "and analyse it; say what is wrong. Exit status 0: fine, 1: warnings, "
                       "2: error.")
    p.add_argument("file", metavar="FILE", help="mechanism file (.toml)")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("fk", help="forward kinematics: actuated coordinates -> pose",
                       description="Platform pose for the actuated coordinates (continuation "
                       "from home); with --all every assembly mode found.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("q", nargs="+", type=float, metavar="Q",
                   help="actuated coordinates [m or rad], in the order of 'analyze'")
    p.add_argument("--all", action="store_true", help="every assembly mode found")
    p.add_argument("--starts", type=int, default=32, help="start assemblies of --all (32)")
    p.add_argument("--seed", type=int, default=0, help="random seed of --all (0)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=cmd_fk)

    p = sub.add_parser("ik", help="inverse kinematics: pose -> actuated coordinates",
                       description="Actuated coordinates at a pose (legs on the working mode "
                       "of home); with --all every working mode.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    _pose_option(p)
    p.add_argument("--all", action="store_true", help="every working mode")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=cmd_ik)

    p = sub.add_parser("map", help="singularity and conditioning maps of a workspace slice",
                       description="Sweep a plane of the pose coordinates (the others at home "
                       "or --fixed); write PREFIX.npz (every array), PREFIX_singularity.png and "
                       "PREFIX_conditioning.png.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    p.add_argument("--plane", choices=sorted(PLANES), default="xy",
                   help="the two varied coordinates (default xy)")
    p.add_argument("--range", nargs=4, type=float, metavar=("A", "B", "C", "D"),
                   help="first coordinate from A to B, second from C to D "
                   "(default: home ± the characteristic length)")
    p.add_argument("--n", type=int, default=50, help="grid points per coordinate (default 50)")
    p.add_argument("--fixed", nargs="+", metavar="NAME=VALUE",
                   help="values of the other coordinates (x y z roll pitch yaw; default home)")
    p.add_argument("--out", metavar="PREFIX", help="output prefix (default map_NAME_PLANE)")
    p.add_argument("--jobs", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--chunk-size", type=int, default=500, help="poses per worker task (500)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd_map)

    p = sub.add_parser("view", help="browser preview (meshcat)",
                       description="Draw the mechanism at a pose (legs, platform, joint screws, "
                       "actuation and constraint wrenches) in a meshcat scene: write it as a "
                       "self-contained HTML page, or open it in the browser.")
    p.add_argument("mechanism", metavar="MECHANISM", help=_MECH_HELP)
    _pose_option(p)
    p.add_argument("--html", metavar="FILE", help="write the page to FILE (no browser)")
    p.add_argument("--open", action="store_true", help="with --html: open it too")
    p.add_argument("--no-screws", action="store_true", help="do not draw the joint screws")
    p.add_argument("--no-wrenches", action="store_true", help="do not draw the wrenches")
    p.set_defaults(func=cmd_view)
    return parser


def main(argv=None) -> int:
    """Entry point of ``pkm-pin``; returns the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # --help (0) or a usage error (2), already printed
        return int(e.code or 0)
    try:
        return args.func(args)
    except PkmError as e:
        message = " ".join(str(e).split("\n"))
        print(f"pkm-pin: error: {message}", file=sys.stderr)
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
