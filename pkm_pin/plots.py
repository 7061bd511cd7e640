"""Maps of a workspace slice drawn with matplotlib (Agg backend: files only, no window).

The data are grids over a plane of the platform pose (two coordinates varied, the others
fixed), shaped ``(n_v, n_u)``: row ``j``, column ``i`` is the pose at ``(u[i], v[j])``.
They come from :meth:`Mechanism.sweep <pkm_pin.sweep>` through ``pkm-pin map``, whose
``.npz`` file holds the same keys as the mapping given to :func:`save_maps`:

* ``u``, ``v``: the coordinates of the columns and rows; ``labels``: their names.
* ``ok``: whether the mechanism assembles at the pose.
* ``det``: signed ``det(A Δ Pᵀ)`` (NaN where not square or not assembled).
* ``type_I``, ``type_II``: the dimensionless closeness indices (0 at the singularity).
* ``singularity``: ``"none"``, ``"I"``, ``"II"``, ``"III"`` (``""`` where not assembled).
* ``condition``: condition number of ``A Δ`` on the platform twists (inf when singular).

Type II loci are the zero level of ``det`` (where its sign changes); type I loci, where
``det`` does not change sign, are drawn as the level ``type_I_level`` of the type I
index (an iso-line near the locus) and as markers on the grid points classified I/III.

:func:`save_class_maps` draws the maps of a sweep whose ``det`` is not defined (a map
over actuated coordinates, or over pose coordinates of a mechanism read over its tree):
the classes with the iso-lines of the general elimination's forward and inverse indices
(:attr:`Analysis.motion_indices`), and the two indices.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from .errors import InputError
from .workspace import KIND_COLOURS

#: Default level of the type I closeness index drawn as the "near type I" iso-line.
TYPE_I_LEVEL = 0.02

_NOT_ASSEMBLED = "0.82"  # grey


def _grids(u, v, **arrays) -> tuple[np.ndarray, np.ndarray, dict]:
    """Check shapes: ``u`` (n_u,), ``v`` (n_v,), each array (n_v, n_u)."""
    u = np.asarray(u, dtype=float).ravel()
    v = np.asarray(v, dtype=float).ravel()
    if u.size < 1 or v.size < 1:
        raise InputError("a map needs at least one value of u and of v")
    out = {}
    for name, a in arrays.items():
        if a is None:
            out[name] = None
            continue
        a = np.asarray(a)
        if a.shape != (v.size, u.size):
            raise InputError(f"{name} must have shape (len(v), len(u)) = {(v.size, u.size)}, "
                             f"got {a.shape}")
        out[name] = a
    return u, v, out


def _figure(title: str, labels: Sequence[str]):
    fig = Figure(figsize=(7.0, 5.6), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_facecolor(_NOT_ASSEMBLED)
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    if title:
        ax.set_title(title)
    return fig, ax


def _contour(ax, u, v, Z, level: float, **style) -> bool:
    """Draw the iso-line ``Z = level`` where Z is finite; whether anything was drawn."""
    Z = np.ma.masked_invalid(np.asarray(Z, dtype=float))
    if min(Z.shape) < 2 or Z.count() < 4 or not (Z.min() < level < Z.max()):
        return False
    ax.contour(u, v, Z, levels=[level], **style)
    return True


def singularity_map(u, v, det, ok, *, type_I=None, singularity=None,
                    labels: Sequence[str] = ("u", "v"), title: str = "",
                    type_I_level: float = TYPE_I_LEVEL, path: str | Path | None = None) -> Figure:
    """Sign of ``det(A Δ Pᵀ)`` over the slice with the type I and type II loci.

    Args:
        u, v: Coordinates of the columns (n_u,) and rows (n_v,).
        det: Signed determinant (n_v, n_u); NaN where undefined.
        ok: Whether the mechanism assembles (n_v, n_u); grey where it does not.
        type_I: Type I closeness index (n_v, n_u), for the near-type-I iso-line.
        singularity: Class strings (n_v, n_u), for markers on singular grid points.
        labels: Axis labels.
        title: Figure title.
        type_I_level: Level of the type I iso-line.
        path: Write the figure there (PNG by the suffix) when given.

    Returns:
        The matplotlib figure.
    """
    u, v, g = _grids(u, v, det=det, ok=ok, type_I=type_I, singularity=singularity)
    ok = g["ok"].astype(bool)
    d = np.asarray(g["det"], dtype=float)
    codes = np.full(d.shape, np.nan)
    codes[ok & (d > 0)] = 2.0
    codes[ok & (d < 0)] = 0.0
    codes[ok & ~np.isfinite(d)] = 1.0
    codes[ok & (d == 0)] = 1.0
    fig, ax = _figure(title or "singularity map: sign of det(A Δ)", labels)
    cmap = ListedColormap(["#f4a582", "#ffffff", "#92c5de"])
    ax.pcolormesh(u, v, np.ma.masked_invalid(codes), cmap=cmap, vmin=-0.5, vmax=2.5,
                  shading="nearest")
    handles = [Patch(color=colour, label=label) for code, colour, label in
               ((2.0, "#92c5de", "det > 0"), (0.0, "#f4a582", "det < 0")) if np.any(codes == code)]
    handles.append(Patch(color=_NOT_ASSEMBLED, label="does not assemble"))
    if np.any(ok & ~np.isfinite(d)):
        handles.append(Patch(facecolor="#ffffff", edgecolor="0.5", label="det undefined"))
    if _contour(ax, u, v, np.where(ok, d, np.nan), 0.0, colors="k", linewidths=1.6):
        handles.append(Line2D([], [], color="k", lw=1.6, label="type II locus (det = 0)"))
    if g["type_I"] is not None and _contour(ax, u, v, np.where(ok, g["type_I"], np.nan),
                                            type_I_level, colors="#b2182b", linewidths=1.2,
                                            linestyles="--"):
        handles.append(Line2D([], [], color="#b2182b", lw=1.2, ls="--",
                              label=f"type I index = {type_I_level:g}"))
    if g["singularity"] is not None:
        s = np.asarray(g["singularity"]).astype(str)
        V, U = np.meshgrid(v, u, indexing="ij")
        for cls, marker, colour, label in ((("I", "III"), "x", "#b2182b", "type I point"),
                                           (("II", "III"), "+", "k", "type II point")):
            hit = np.isin(s, cls)
            if np.any(hit):
                ax.plot(U[hit], V[hit], marker, color=colour, ms=5, ls="none")
                handles.append(Line2D([], [], marker=marker, color=colour, ls="none",
                                      label=label))
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
    ax.set_aspect("equal", adjustable="box")
    if path is not None:
        fig.savefig(path)
    return fig


def conditioning_map(u, v, condition, ok, *, det=None, labels: Sequence[str] = ("u", "v"),
                     title: str = "", path: str | Path | None = None) -> Figure:
    """``log10`` of the condition number of ``A Δ`` over the slice.

    Args:
        u, v: Coordinates of the columns (n_u,) and rows (n_v,).
        condition: Condition numbers (n_v, n_u), inf where singular (drawn in the
            colour map's "over" colour).
        ok: Whether the mechanism assembles (n_v, n_u); grey where it does not.
        det: Signed determinant, to draw the type II locus (det = 0) when given.
        labels: Axis labels.
        title: Figure title.
        path: Write the figure there when given.

    Returns:
        The matplotlib figure.
    """
    u, v, g = _grids(u, v, condition=condition, ok=ok, det=det)
    ok = g["ok"].astype(bool)
    c = np.asarray(g["condition"], dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        logc = np.log10(np.where(ok, c, np.nan))
    finite = logc[np.isfinite(logc)]
    top = float(min(max(finite.max(), 1.0), 8.0)) if finite.size else 1.0
    logc = np.where(np.isposinf(logc), top + 1.0, logc)
    fig, ax = _figure(title or "conditioning map: log10 cond(A Δ)", labels)
    cmap = colormaps["viridis"].with_extremes(over="#d7191c")
    mesh = ax.pcolormesh(u, v, np.ma.masked_invalid(logc), cmap=cmap, vmin=0.0, vmax=top,
                         shading="nearest")
    fig.colorbar(mesh, ax=ax, extend="max", label="log10 condition number")
    handles = [Patch(color=_NOT_ASSEMBLED, label="does not assemble")]
    if np.any(np.isposinf(np.where(ok, c, 0.0))):
        handles.append(Patch(color="#d7191c", label="singular (inf)"))
    if g["det"] is not None and _contour(ax, u, v, np.where(ok, g["det"], np.nan), 0.0,
                                         colors="w", linewidths=1.4):
        handles.append(Line2D([], [], color="w", lw=1.4, label="type II locus (det = 0)"))
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85,
              facecolor="0.6")
    ax.set_aspect("equal", adjustable="box")
    if path is not None:
        fig.savefig(path)
    return fig


def save_maps(data: Mapping, prefix: str | Path, title: str = "") -> list[Path]:
    """Write ``PREFIX_singularity.png`` and ``PREFIX_conditioning.png`` from map data.

    Args:
        data: A mapping with the keys of this module's docstring (e.g. ``np.load`` of
            the ``.npz`` written by ``pkm-pin map``).
        prefix: Path prefix of the files.
        title: Prefix of the figure titles (e.g. the mechanism name).

    Returns:
        The two paths written.
    """
    missing = [k for k in ("u", "v", "ok", "det", "condition") if k not in data]
    if missing:
        raise InputError(f"map data lacks the keys {missing}")
    labels = [str(x) for x in data["labels"]] if "labels" in data else ["u", "v"]
    prefix = Path(prefix)
    sing = prefix.with_name(prefix.name + "_singularity.png")
    cond = prefix.with_name(prefix.name + "_conditioning.png")
    head = f"{title}: " if title else ""
    singularity_map(data["u"], data["v"], data["det"], data["ok"],
                    type_I=data["type_I"] if "type_I" in data else None,
                    singularity=data["singularity"] if "singularity" in data else None,
                    labels=labels, title=f"{head}sign of det(A Δ), singularity loci",
                    path=sing)
    conditioning_map(data["u"], data["v"], data["condition"], data["ok"], det=data["det"],
                     labels=labels, title=f"{head}log10 cond(A Δ)", path=cond)
    return [sing, cond]


# ------------------------------------------------------------------- workspaces
# ------------------------------------------------ class and index maps
#: Colours of the singularity classes in :func:`save_class_maps`.
CLASS_COLOURS = {"none": "#ffffff", "I": "#f4a582", "II": "#92c5de", "III": "#b2abd2"}
#: Level of the forward and inverse indices drawn as iso-lines on the class map.
ISO_LEVEL = 0.05


def save_class_maps(data: Mapping, prefix: str | Path, title: str = "") -> list[Path]:
    """PNG maps of the classes and the forward and inverse indices of a sweep over two
    coordinates (``pkm-pin map`` over actuated coordinates, or over pose coordinates of a
    mechanism read over its tree: the general elimination's indices).

    Two varied coordinates (``u``, ``v`` and arrays shaped (n_v, n_u)): writes
    ``PREFIX_singularity.png`` (the class of each grid point, grey where it does not
    assemble, with the iso-lines :data:`ISO_LEVEL` of the forward and inverse indices) and
    ``PREFIX_indices.png`` (the forward and inverse indices). One coordinate (``u`` and
    arrays (n_u,)): ``PREFIX_indices.png`` only, the two indices along it.

    Returns:
        The paths written.
    """
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


def _workspace_codes(ws) -> tuple[np.ndarray, list[str]]:
    """Per cell, the index of the smallest kind it belongs to (nan: not reachable)."""
    codes, kinds = ws.smallest_kind()
    return np.where(codes >= 0, codes, np.nan), kinds


def _workspace_panel(ax, ws, codes2, kinds, u, v, labels, centre=None) -> None:
    cmap = ListedColormap([KIND_COLOURS[k] for k in kinds])
    ax.set_facecolor(_NOT_ASSEMBLED)
    ax.pcolormesh(u, v, np.ma.masked_invalid(codes2.T), cmap=cmap, vmin=-0.5,
                  vmax=len(kinds) - 0.5, shading="nearest")
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
    if centre is not None:
        ax.plot([centre[0]], [centre[1]], "k+", ms=9)


def workspace_plots(ws, prefix: str | Path, title: str = "") -> list[Path]:
    """PNG pictures of a gridded :class:`~pkm_pin.workspace.Workspace`.

    Two coordinates: ``PREFIX_workspace.png``, the cells coloured by the smallest kind
    they belong to (reachable, singularity-free, good transmission; grey: not
    reachable), the home cell marked and the largest inscribed square of the smallest
    non-empty kind drawn. Three: ``PREFIX_slices.png``, up to 6 slices at values of the
    third coordinate. One: a strip. Sobol samples: a scatter of the first two.

    Returns:
        The paths written.
    """
    prefix = Path(prefix)
    codes, kinds = _workspace_codes(ws)
    labels = [f"{c} [{u}]" for c, u in zip(ws.coords, ws.units)]
    handles = [Patch(color=KIND_COLOURS[k], label=k) for k in kinds]
    handles.append(Patch(color=_NOT_ASSEMBLED, label="not reachable"))
    head = f"{title}: " if title else ""
    k = len(ws.coords)
    if ws.sampling != "grid" or k == 1:
        fig, ax = _figure(f"{head}workspace samples", labels + ["-"] * (2 - min(k, 2)))
        P = ws.points
        y = P[:, 1] if k > 1 else np.zeros(len(P))
        flat = codes.ravel()
        for i, kind in enumerate(kinds):
            hit = flat == i
            ax.plot(P[hit, 0], y[hit], ".", color=KIND_COLOURS[kind], ms=3)
        ax.legend(handles=handles, loc="upper right", fontsize=8)
        path = prefix.with_name(prefix.name + "_workspace.png")
        fig.savefig(path)
        return [path]
    if k == 2:
        fig, ax = _figure(f"{head}workspace over {ws.coords[0]}, {ws.coords[1]}", labels)
        _workspace_panel(ax, ws, codes, kinds, ws.axes[0], ws.axes[1], labels, ws.home)
        smallest = next((kd for kd in reversed(kinds) if ws.masks[kd].any()), None)
        shape = ws.inscribed.get(smallest) if smallest else None
        if shape is not None and np.isfinite(shape.cube) and shape.cube > 0:
            c, a = shape.centre, shape.cube
            ax.plot(c[0] + a * np.array([-1, 1, 1, -1, -1]),
                    c[1] + a * np.array([-1, -1, 1, 1, -1]), "k-", lw=1.2)
            handles.append(Line2D([], [], color="k", lw=1.2,
                                  label=f"largest square ({smallest})"))
        ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.85)
        if ws.units[0] == ws.units[1]:
            ax.set_aspect("equal", adjustable="box")
        path = prefix.with_name(prefix.name + "_workspace.png")
        fig.savefig(path)
        return [path]
    n3 = ws.shape[2]
    picks = np.unique(np.linspace(0, n3 - 1, min(6, n3)).round().astype(int))
    fig = Figure(figsize=(11.0, 7.0), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    cols = min(3, len(picks))
    rows = int(np.ceil(len(picks) / cols))
    for i, s in enumerate(picks):
        ax = fig.add_subplot(rows, cols, i + 1)
        _workspace_panel(ax, ws, codes[:, :, s], kinds, ws.axes[0], ws.axes[1], labels)
        ax.set_title(f"{ws.coords[2]} = {ws.axes[2][s]:.4g} {ws.units[2]}", fontsize=9)
        if ws.units[0] == ws.units[1]:
            ax.set_aspect("equal", adjustable="box")
    fig.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize=8)
    fig.suptitle(f"{head}workspace slices")
    path = prefix.with_name(prefix.name + "_slices.png")
    fig.savefig(path)
    return [path]


# ------------------------------------------------------------------ trajectories
def _against_time(st, values: np.ndarray, units, what: str, title: str, path: Path) -> Path:
    """One curve per actuator of ``values`` (N, n) against time, the unit in the legend."""
    fig, ax = _figure(title, ("t [s]", what))
    ax.set_facecolor("white")
    ax.grid(True, lw=0.4, alpha=0.6)
    for k, name in enumerate(st.actuated):
        ax.plot(st.t, values[:, k], lw=1.3, label=f"{name} [{units[k]}]")
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    fig.savefig(path)
    return path


def trajectory_plots(st, prefix: str | Path, title: str = "") -> list[Path]:
    """PNG pictures of a :class:`~pkm_pin.trajectory.TrajectoryStudy`:
    ``PREFIX_efforts.png``, ``PREFIX_speeds.png``, ``PREFIX_powers.png`` (one curve per
    actuator against time) and ``PREFIX_torque_speed.png`` (each actuator's (speed,
    effort) points, one panel per actuator, coloured by time, with its peak effort and
    peak speed as a dashed box: the operating points a motor's torque–speed curve
    must cover).

    Returns:
        The paths written.
    """
    prefix = Path(prefix)
    head = f"{title}: " if title else ""

    def name(tag: str) -> Path:
        return prefix.with_name(f"{prefix.name}_{tag}.png")

    out = [_against_time(st, st.efforts, st.effort_units, "effort", f"{head}actuator efforts",
                         name("efforts")),
           _against_time(st, st.speeds, st.speed_units, "speed", f"{head}actuator speeds",
                         name("speeds")),
           _against_time(st, st.powers, ["W"] * len(st.actuated), "power [W]",
                         f"{head}actuator powers (τ q̇)", name("powers"))]
    n = len(st.actuated)
    cols = min(3, max(n, 1))
    rows = max(1, int(np.ceil(n / cols)))
    fig = Figure(figsize=(3.6 * cols + 1.0, 3.2 * rows + 0.6), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    points = None
    for k, actuator in enumerate(st.actuated):
        ax = fig.add_subplot(rows, cols, k + 1)
        ax.grid(True, lw=0.4, alpha=0.6)
        x, y = st.speeds[:, k], st.efforts[:, k]
        points = ax.scatter(x, y, c=st.t, s=6, cmap=colormaps["viridis"])
        px, py = np.abs(x).max(), np.abs(y).max()
        ax.plot([-px, px, px, -px, -px], [-py, -py, py, py, -py], "--", color="0.4", lw=0.8)
        ax.set_xlabel(f"speed [{st.speed_units[k]}]")
        ax.set_ylabel(f"effort [{st.effort_units[k]}]")
        ax.set_title(actuator, fontsize=9)
    if points is not None:
        fig.colorbar(points, ax=fig.axes, label="t [s]", shrink=0.8)
    fig.suptitle(f"{head}torque–speed points (dashed: peak effort × peak speed)")
    path = name("torque_speed")
    fig.savefig(path)
    out.append(path)
    return out
