"""Reports of a general linkage (:class:`~pkm_pin.linkage.Linkage`) at one configuration:
plain data (JSON), text and Markdown; and the maps of ``pkm-pin map`` over two actuated
coordinates.

A linkage report holds what :class:`~pkm_pin.linkage.LinkageAnalysis` knows about one
assembly: the whole tree's configuration (joint by joint), the output frame and its pose,
the mobility (DOF, idle DOF with each idle motion in words, redundant closure equations,
Grübler's count, the actuated joints that can be driven independently), the output's
motion type with a readable basis of its twists and of its constraint wrenches (see
:func:`pkm_pin.report.readable_basis`, about the output frame's origin), ``A`` and ``B``
of ``A Δ t = B q̇_a``, the singularity class and the indices.

Conventions as :mod:`pkm_pin.report`: screws axis-first about the world origin, twists
``(ω; v_O)``, wrenches ``(f; m_O)``; lengths [m], angles [rad]. Poses are the output
frame's placement: ``xyz`` [m] and URDF ``rpy`` [rad]. In the plain data, an index that
is undefined (NaN) or infinite is ``None`` (JSON ``null``), so the JSON is standard.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .report import (  # the one report (moved from here), and what fk and maps print
    _list,
    assembly_data,
    body_frames,
    failed_lines,
    joint_values,
    joints_lines,
    linkage_markdown,
    linkage_report_data,
    output_hint,
    output_line,
    pose_dict,
    structure_data,
    structure_line,
    submechanism_lines,
    submechanisms_data,
    undefined_indices,
)
from .report import text as linkage_text

#: Names of :mod:`pkm_pin.report` kept here too (the report of a linkage was written
#: here before there was one report for every mechanism), and this module's own.
__all__ = ["CLASS_COLOURS", "ISO_LEVEL", "assembly_data", "body_frames", "fk_submechanisms_data",
           "fk_text", "joint_values", "linkage_markdown", "linkage_report_data",
           "linkage_text", "output_hint", "output_line", "pose_dict", "save_linkage_maps",
           "structure_data", "structure_line", "submechanism_lines", "submechanisms_data",
           "undefined_indices"]

#: Colours of the singularity classes in the maps.
CLASS_COLOURS = {"none": "#ffffff", "I": "#f4a582", "II": "#92c5de", "III": "#b2abd2"}
#: Level of the forward and inverse indices drawn as iso-lines on the class map.
ISO_LEVEL = 0.05


def fk_text(r: dict) -> str:
    """Text of ``pkm-pin fk`` / ``ik`` for a linkage from :func:`assembly_data` (and,
    for several independent sub-mechanisms, the ``submechanisms`` of
    :func:`fk_submechanisms_data`: each one's actuated values and output pose)."""
    out = [f"mechanism  {r['mechanism']}",
           f"actuated   {_actuated_words(r)}",
           f"output     {r['output']}{' (point)' if r['output_is_point'] else ''}: "
           f"xyz {_list(r['pose']['xyz'])}  rpy {_list(r['pose']['rpy'])}"]
    subs = r.get("submechanisms") or []
    if subs:
        out.append(f"sub-mechanisms  {len(subs)} independent, each with its own output "
                   "(fk --sub K Q…: the actuated values of sub-mechanism K alone, the "
                   "others held at the reference assembly):")
        for k, s in enumerate(subs):
            out += [f"    [{k}] {s['name']}: {_actuated_words(s)}",
                    f"        output {s['output']}: xyz {_list(s['pose']['xyz'])}  "
                    f"rpy {_list(s['pose']['rpy'])}"]
    out.append("joints (q):")
    return "\n".join(out + joints_lines(r) + [f"residual   {r['residual']:.2g}"]
                     + failed_lines(r))


def _actuated_words(r: dict) -> str:
    """``a, b = [values]``, or that there is no actuator."""
    if not r["actuated"]:
        return "none (no actuator: the assembly from the reference configuration)"
    return f"{', '.join(r['actuated'])} = {_list(r['q_actuated'])}"


def fk_submechanisms_data(link, subs, assembly) -> list:
    """For ``fk`` of a linkage with several independent sub-mechanisms ``subs``
    (:meth:`Linkage.submechanisms`), at the whole linkage's ``assembly``: each one's
    ``{"name", "actuated", "q_actuated", "output", "pose"}`` (its actuated values and its
    output frame's pose, read in the whole tree); ``[]`` for one mechanism."""
    if len(subs) <= 1:
        return []
    model = link.model
    kin = model.kinematics(assembly.q)
    values = dict(zip(link.actuated, assembly.q_actuated))
    out = []
    for sub in subs:
        M = kin.frame_placements[model.tree.getFrameId(sub.output)]
        out.append({"name": sub.name, "actuated": list(sub.actuated),
                    "q_actuated": [float(values[n]) for n in sub.actuated],
                    "output": sub.output, "pose": pose_dict(M)})
    return out


# ------------------------------------------------------------------------- maps
def save_linkage_maps(data: Mapping, prefix: str | Path, title: str = "") -> list[Path]:
    """PNG maps of a sweep over actuated coordinates (``pkm-pin map`` of a linkage).

    Two varied coordinates (``u``, ``v`` and arrays shaped (n_v, n_u)): writes
    ``PREFIX_singularity.png`` (the class of each grid point, grey where it does not
    assemble, with the iso-lines :data:`ISO_LEVEL` of the forward and inverse indices) and
    ``PREFIX_indices.png`` (the forward and inverse indices). One coordinate (``u`` and
    arrays (n_u,)): ``PREFIX_indices.png`` only, the two indices along it.

    Returns:
        The paths written.
    """
    from .plots import _figure

    prefix = Path(prefix)
    labels = [str(x) for x in data["labels"]]
    head = f"{title}: " if title else ""
    indices = prefix.with_name(prefix.name + "_indices.png")
    if "v" not in data:
        fig, ax = _figure(f"{head}forward and inverse indices", [labels[0], "index"])
        ax.set_facecolor("white")
        for key, colour in (("forward", "#2166ac"), ("inverse", "#b2182b")):
            ax.plot(data["u"], data[key], color=colour, label=f"{key} index")
        ax.legend(fontsize=8)
        fig.savefig(indices)
        return [indices]
    sing = prefix.with_name(prefix.name + "_singularity.png")
    _class_map(data, labels, f"{head}singularity classes", sing)
    _index_maps(data, labels, head, indices)
    return [sing, indices]


def _class_map(data: Mapping, labels: list, title: str, path: Path) -> None:
    from matplotlib.colors import ListedColormap
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from .plots import _contour, _figure

    u, v, ok = data["u"], data["v"], np.asarray(data["converged"], bool)
    cls = np.asarray(data["singularity"]).astype(str)
    names = list(CLASS_COLOURS)
    codes = np.full(cls.shape, np.nan)
    for k, name in enumerate(names):
        codes[ok & (cls == name)] = k
    fig, ax = _figure(title, labels)
    ax.pcolormesh(u, v, np.ma.masked_invalid(codes), cmap=ListedColormap(list(
        CLASS_COLOURS.values())), vmin=-0.5, vmax=len(names) - 0.5, shading="nearest")
    handles = [Patch(facecolor=c, edgecolor="0.5", label=f"class {n}")
               for n, c in CLASS_COLOURS.items() if np.any(ok & (cls == n))]
    for key, colour in (("forward", "k"), ("inverse", "#b2182b")):
        if _contour(ax, u, v, np.where(ok, data[key], np.nan), ISO_LEVEL, colors=colour,
                    linewidths=1.2):
            handles.append(Line2D([], [], color=colour, lw=1.2,
                                  label=f"{key} index = {ISO_LEVEL:g}"))
    handles.append(Patch(color="0.82", label="does not assemble"))
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
    fig.savefig(path)


def _index_maps(data: Mapping, labels: list, head: str, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(11.0, 4.8), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    ok = np.asarray(data["converged"], bool)
    for k, key in enumerate(("forward", "inverse")):
        ax = fig.add_subplot(1, 2, k + 1)
        ax.set_facecolor("0.82")
        mesh = ax.pcolormesh(data["u"], data["v"],
                             np.ma.masked_invalid(np.where(ok, data[key], np.nan)),
                             vmin=0.0, vmax=1.0, cmap="viridis", shading="nearest")
        fig.colorbar(mesh, ax=ax)
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        ax.set_title(f"{head}{key} index (0: singular)")
    fig.savefig(path)
