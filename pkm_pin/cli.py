"""Command-line interface ``pkm-pin``.

User mistakes print one line ``pkm-pin: error: …`` on stderr and exit with status 2;
no Python traceback.
"""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

from .errors import PkmError


def _load(path: str | None):
    from .mechanism import load_mechanism

    if path is None:
        from .builders import MECHANISMS

        return MECHANISMS["rpr3"]().build()
    return load_mechanism(path)


def analysis_report(analysis) -> dict:
    """Plain-data summary of an :class:`~pkm_pin.analysis.Analysis` (JSON-ready)."""
    from .crosscheck import crosscheck

    checks = crosscheck(analysis)
    pose = analysis.assembly.pose
    import pinocchio as pin

    return {
        "mechanism": analysis.mechanism.name,
        "pose": {"xyz": pose.translation.tolist(),
                 "rpy": pin.rpy.matrixToRpy(pose.rotation).tolist()},
        "dof": analysis.dof,
        "motion_type": analysis.motion_type,
        "grubler": analysis.grubler,
        "redundant_constraints": analysis.redundant_constraints,
        "platform_twists": analysis.platform_twists.tolist(),
        "actuated": analysis.mechanism.actuated_names,
        "A": analysis.A.tolist(),
        "B": analysis.B.tolist(),
        "singularity": analysis.singularity,
        "constraint_singular": bool(analysis.constraint_singular),
        "indices": analysis.indices,
        "crosscheck": checks,
        "crosscheck_max_error": None if checks is None else max(checks.values()),
    }


def _matrix(M) -> str:
    return "\n".join("    " + " ".join(f"{x:10.5f}" for x in row) for row in np.atleast_2d(M))


def _print_text(r: dict) -> None:
    print(f"mechanism          {r['mechanism']}")
    print(f"pose               xyz {np.round(r['pose']['xyz'], 6).tolist()}  "
          f"rpy {np.round(r['pose']['rpy'], 6).tolist()}")
    print(f"DOF                {r['dof']}  ({r['motion_type']})")
    print(f"Grübler count      {r['grubler']}  (redundant constraints: "
          f"{r['redundant_constraints']})")
    print("platform twists (ω; v_O):\n" + _matrix(r["platform_twists"]))
    print(f"actuated joints    {', '.join(r['actuated'])}")
    print("A (actuation wrenches (f; m_O), A Δ t = B q̇_a):\n" + _matrix(r["A"]))
    print("B:\n" + _matrix(r["B"]))
    print(f"singularity        {r['singularity']}"
          + ("  (constraint singular)" if r["constraint_singular"] else ""))
    print("indices            " + ", ".join(f"{k} = {v:.6g}" for k, v in r["indices"].items()))
    if r["crosscheck"] is None:
        print("cross-check        no hand-written formulas for this mechanism")
    else:
        print(f"cross-check        max |Pinocchio − formulas| = {r['crosscheck_max_error']:.3g}  "
              + "(" + ", ".join(f"{k} {v:.2g}" for k, v in r["crosscheck"].items()) + ")")


def cmd_analyze(args) -> int:
    mech = _load(args.mechanism)
    pose = mech.home if args.pose is None else args.pose
    analysis = mech.analyze(pose)
    report = analysis_report(analysis)
    if args.json:
        print(json.dumps(report, indent=2, default=float))
    else:
        _print_text(report)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pkm-pin",
        description="Screw-theory analysis of parallel kinematic machines (Pinocchio).",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    p = sub.add_parser("analyze", help="mobility, Jacobians and singularity of one pose",
                       description="Analyse a mechanism at a pose (default: its home pose). "
                       "With no file: the built-in 3-RPR of seed 000.")
    p.add_argument("mechanism", nargs="?", help="mechanism file (.toml)")
    p.add_argument("--pose", nargs=6, type=float, metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                   help="platform pose [m, rad] (default: the home pose)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_analyze)
    return parser


def main(argv=None) -> int:
    """Entry point of ``pkm-pin``."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except PkmError as e:
        print(f"pkm-pin: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
