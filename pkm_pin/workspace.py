"""Workspaces: where a mechanism reaches, where it is free of singularities, where it
transmits well, with their volumes and the largest cube and cylinder they hold.

The workspace is sampled over some of the platform's pose coordinates (x, y, z [model
length unit], roll, pitch, yaw [rad]; default the mechanism's independent coordinates,
:func:`default_coordinates`), the other coordinates fixed (given by ``at`` or held at
home), inside a box ``bounds``:

* ``sampling="grid"``: ``n`` cells per coordinate; each cell is sampled at its centre,
  so the cells tile the box exactly and every volume is a volume *inside the box*;
* ``sampling="sobol"``: ``samples`` scrambled Sobol points (seeded, :mod:`scipy.stats.qmc`).

Every sample is assembled and analysed by the sweep engine (:func:`pkm_pin.sweep.sweep`:
compiled legs, chunks, any executor including a Dask client, a progress bar). Kinds:

* ``"reachable"``: the samples that assemble within the joint limits;
* ``"singularity-free"``: on a grid, the cells connected to the home cell (faces shared)
  through cells that assemble with the home DOF, with no type I / II / III singularity
  (:attr:`SweepResult.singularity` "none") and with the same sign of the carried
  determinant ``det(A Δ)`` as home (:attr:`SweepResult.det`): a grid step across a type
  II locus changes its sign even when no sample falls on it. With Sobol points there is
  no neighbourhood: the samples with those properties (connectivity not checked);
* ``"transmission"``: the singularity-free workspace where the local transmission index
  LTI (:mod:`pkm_pin.transmission`) and, where it is defined, the constraint
  transmission index CTI are at least ``threshold`` (0.7): ``min(LTI, CTI) ≥ 0.7``; again
  the part connected to home (empty when home itself transmits worse). A general
  linkage's CTI is :meth:`Linkage.transmission`'s (per actuator side of its loops).

Volumes (:class:`Volume`; an area for two coordinates, a product of units for mixed
coordinates) on a grid are the cell count times the cell volume, with a bracket: a cell
is a *boundary cell* when one of its 3^k − 1 neighbours (diagonals included) disagrees
with it; the true volume lies between the volume of the inside cells that are not on
the boundary and that plus every boundary cell, provided the workspace has no feature
thinner than two cells (``error`` = the larger distance from the count to the bracket's
ends, about half the boundary cells; it falls like the cell size). With Sobol points the
volume is the fraction inside times the box volume and ``error`` three binomial standard
errors (conservative: quasi-random points converge faster than random ones).

Inscribed shapes (:class:`Inscribed`), centred on ``centre`` (default home) inside a
kind's workspace: the largest axis-aligned cube (square in 2-D) and, in 3-D, the
cylinder of largest volume whose axis is along z (else the last coordinate) — what a
machine-tool designer sizes a machine by. A cell that is not in the workspace, and the
outside of the box, bound them; they are exact for the grid's cells (a shape touches the
nearest cell that is out) and ``error`` is one cell size.

General linkages (:class:`~pkm_pin.linkage.Linkage`, :func:`linkage_workspace`) are
sampled over the output point's coordinates (inverse kinematics) or over actuated
coordinates (forward kinematics). The closure solver goes from cell to cell from the home
(reference) cell, each cell warm-started from its solved neighbours, with the solver's
restarts where they fail: the workspace found is the one connected to home.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Mapping, Sequence
from concurrent.futures import Executor, as_completed
from dataclasses import dataclass, field, replace
from typing import NamedTuple

import numpy as np
import pinocchio as pin

from . import screws
from .checkpoint import recording
from .errors import InputError, PkmError
from .model.closure_model import pose_rows
from .solve import POSE_COORDINATES

#: The pose coordinates, in the order of the sweep arrays.
COORDINATES = POSE_COORDINATES
#: Workspace kinds, from the largest set to the smallest.
KINDS = ("reachable", "singularity-free", "transmission")
#: Their colours in pictures (the plots and the 3-D cloud).
KIND_COLOURS = {"reachable": "#fdb863", "singularity-free": "#4393c3",
                "transmission": "#1a9850"}
#: Largest number of coordinates sampled at once.
MAX_COORDINATES = 3
#: Default half range of an angle [rad] when no bounds are given.
ANGLE_HALF_RANGE = 0.5
#: Parasitic coordinates whose completed values stay within this of home (lengths
#: relative to the characteristic length, angles [rad]) at every probe are taken as
#: constant: the workspace's poses are then full poses (the fast path of the sweep).
CONSTANT_COORDINATE_TOL = 1e-9


@dataclass(frozen=True)
class Volume:
    """A workspace's volume (area for two coordinates) with its stated accuracy.

    Attributes:
        value: Grid: the refined volume (the boundary cells counted by the fraction of
            their ``subsamples``-per-coordinate sub-grid inside; module docstring), or
            the cell count × cell volume without sub-sampling; Sobol: inside fraction ×
            box volume.
        error: Stated accuracy of ``value`` (module docstring): grid, the bracket's half
            width on the sub-grid; Sobol, three binomial standard errors.
        lower, upper: The bracket of the cells (grid), or ``value ∓ error`` (Sobol).
        cells: Samples inside.
        boundary_cells: Boundary cells (grid; 0 for Sobol).
        unit: Unit of the volume, e.g. ``"m^3"``, ``"m^2·rad"``.
        count: Cell count × cell volume (grid; Sobol: ``value``).
        subsamples: Sub-points per coordinate of each boundary cell (1: none).
    """

    value: float
    error: float
    lower: float
    upper: float
    cells: int
    boundary_cells: int
    unit: str
    count: float = float("nan")
    subsamples: int = 1

    def as_dict(self) -> dict:
        """Plain data (for JSON)."""
        return {"value": self.value, "error": self.error, "lower": self.lower,
                "upper": self.upper, "cells": self.cells,
                "boundary_cells": self.boundary_cells, "unit": self.unit,
                "count": self.count, "subsamples": self.subsamples}


@dataclass(frozen=True)
class Inscribed:
    """The largest shapes centred on ``centre`` inside a workspace (module docstring).

    Attributes:
        centre: (k,) their centre in the workspace coordinates.
        cube: Half side of the largest axis-aligned cube (square in 2-D) [unit of the
            coordinates]; nan when the coordinates have different units.
        cylinder_radius, cylinder_half_height: The cylinder of largest volume with its
            axis along ``axis`` through the centre (3-D, the other two coordinates of
            one unit); in 2-D the radius is the largest disc's, the half height nan.
        axis: The cylinder's axis coordinate.
        error: Accuracy of each size: one cell (the largest spacing); with Sobol
            points the typical spacing.
    """

    centre: np.ndarray
    cube: float
    cylinder_radius: float
    cylinder_half_height: float
    axis: str
    error: float

    def as_dict(self) -> dict:
        """Plain data (for JSON)."""
        return {"centre": [float(c) for c in self.centre], "cube_half_side": self.cube,
                "cylinder_radius": self.cylinder_radius,
                "cylinder_half_height": self.cylinder_half_height, "axis": self.axis,
                "error": self.error}


@dataclass(frozen=True, eq=False)
class Workspace:
    """A sampled workspace (:func:`workspace`, :func:`linkage_workspace`).

    Attributes:
        mechanism: The mechanism's name.
        coords: The sampled coordinates (pose coordinates, or actuated joint names).
        units: Their units (``"m"``/``"mm"``… or ``"rad"``).
        bounds: (k, 2) the box.
        sampling: ``"grid"`` or ``"sobol"``.
        axes: Grid: the cell centres of each coordinate (``()`` for Sobol).
        shape: Grid: ``(n_1, …, n_k)``; Sobol: ``(N,)``. Every per-sample array has it.
        points: (N, k) the samples (grid: cells in C order of ``shape``).
        fixed: The other coordinates and their values (given or held at home).
        home: (k,) the home coordinates.
        masks: Kind → boolean array (``shape``): the samples in that workspace.
        values: Per-sample arrays: ``ok``, ``singularity`` (class), ``det`` (carried
            determinant), ``lti``, ``cti`` (nan where not computed or not defined).
        volumes: Kind → :class:`Volume`.
        inscribed: Kind → :class:`Inscribed` (the singularity-free and transmission
            workspaces; the reachable one too).
        counts: Samples, assembled, failures, the kinds' samples, ``on_bounds`` (reachable
            samples on the box's faces: the reachable workspace extends beyond the box).
        timing: Seconds: ``evaluate`` (assembly and analysis), ``masks``, ``total``;
            ``poses_per_s``.
        threshold: The ``min(LTI, CTI)`` threshold of the transmission workspace.
        method: How the samples were evaluated: ``"poses"`` (full poses, the sweep's
            fast path), ``"completed poses"`` (partial poses completed on the motion),
            ``"linkage output"``, ``"linkage actuated"``.
    """

    mechanism: str
    coords: tuple
    units: tuple
    bounds: np.ndarray
    sampling: str
    axes: tuple
    shape: tuple
    points: np.ndarray = field(repr=False)
    fixed: dict
    home: np.ndarray
    masks: dict = field(repr=False)
    values: dict = field(repr=False)
    volumes: dict
    inscribed: dict
    counts: dict
    timing: dict
    threshold: float
    method: str

    @property
    def spacing(self) -> np.ndarray:
        """(k,) cell sizes (grid; the typical spacing of the samples for Sobol)."""
        span = self.bounds[:, 1] - self.bounds[:, 0]
        if self.sampling == "grid":
            return span / np.array(self.shape, float)
        return span * len(self.points) ** (-1.0 / len(self.coords))

    def smallest_kind(self) -> tuple[np.ndarray, list[str]]:
        """``(codes, kinds)``: the kinds computed, largest set first, and per sample
        (the samples' shape) the index in ``kinds`` of the smallest it belongs to
        (−1: not reachable)."""
        kinds = [k for k in KINDS if k in self.masks]
        codes = np.full(np.shape(self.masks[kinds[0]]) if kinds else len(self.points), -1)
        for i, k in enumerate(kinds):
            codes[np.asarray(self.masks[k])] = i
        return codes, kinds

    def as_dict(self) -> dict:
        """Plain data (JSON; nan and inf as None): coordinates, bounds, volumes,
        inscribed shapes, counts, timing."""
        return _plain({"mechanism": self.mechanism, "coords": list(self.coords),
                "units": list(self.units), "bounds": self.bounds.tolist(),
                "sampling": self.sampling, "shape": list(self.shape),
                "fixed": {k: float(v) for k, v in self.fixed.items()},
                "home": self.home.tolist(), "threshold": self.threshold,
                "method": self.method,
                "volumes": {k: v.as_dict() for k, v in self.volumes.items()},
                "inscribed": {k: v.as_dict() for k, v in self.inscribed.items()},
                "counts": dict(self.counts), "timing": dict(self.timing)})


def _plain(x):
    """JSON-safe data: non-finite numbers become None."""
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(x) else None
    return x


# ================================================================ grid algebra
def grid_axes(bounds: np.ndarray, n) -> tuple[np.ndarray, ...]:
    """Cell centres ``lo + (i + ½) h`` of ``n`` cells per coordinate (an int, or one
    per coordinate) tiling each interval of ``bounds`` (k, 2)."""
    ns = np.broadcast_to(np.asarray(n), (len(bounds),))
    out = []
    for (lo, hi), m in zip(bounds, ns):
        m = int(m)
        if m < 2:
            raise InputError(f"a workspace grid needs at least 2 cells per coordinate, got {m}")
        h = (hi - lo) / m
        out.append(lo + (np.arange(m) + 0.5) * h)
    return tuple(out)


def grid_points(axes: Sequence[np.ndarray]) -> np.ndarray:
    """(N, k) the cells of a grid in C order (the last coordinate fastest)."""
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


def boundary_cells(mask: np.ndarray) -> np.ndarray:
    """Cells one of whose 3^k − 1 neighbours (diagonals included) disagrees with them;
    the box's faces are not a boundary (the box is the domain)."""
    from scipy import ndimage

    mask = np.asarray(mask, bool)
    full = ndimage.generate_binary_structure(mask.ndim, mask.ndim)
    inner = ndimage.binary_erosion(mask, full, border_value=1)
    outer = ndimage.binary_dilation(mask, full)
    return (mask & ~inner) | (~mask & outer)


def grid_volume(mask: np.ndarray, spacing: np.ndarray, unit: str) -> Volume:
    """:class:`Volume` of the cells of ``mask`` (cells of sizes ``spacing``) with its
    bracket (module docstring)."""
    mask = np.asarray(mask, bool)
    cell = float(np.prod(spacing))
    edge = boundary_cells(mask)
    n_in, n_in_edge, n_out_edge = int(mask.sum()), int((mask & edge).sum()), \
        int((~mask & edge).sum())
    value = n_in * cell
    lower, upper = (n_in - n_in_edge) * cell, (n_in + n_out_edge) * cell
    return Volume(value, max(value - lower, upper - value), lower, upper, n_in,
                  n_in_edge + n_out_edge, unit, value)


def subcell_offsets(k: int, sub: int) -> np.ndarray:
    """(sub^k, k) the centres of a ``sub``-per-coordinate sub-grid of a unit cell, in
    cell units from its lower corner (C order, last coordinate fastest)."""
    s = (np.arange(sub) + 0.5) / sub
    return np.stack(np.meshgrid(*([s] * k), indexing="ij"), -1).reshape(-1, k)


def refined_volume(mask: np.ndarray, spacing: np.ndarray, unit: str, sub: int,
                   inside: Mapping) -> Volume:
    """:class:`Volume` of ``mask`` with its boundary cells sub-sampled (module
    docstring): ``inside`` maps each boundary cell's flat index to its (sub^k,) sub-grid
    values (:func:`subcell_offsets` order; a cell missing keeps its own value). The value
    is the count on the ``sub`` times finer grid whose cells are the sub-points (the
    others take their cell's value), the error that grid's bracket half width, the
    bracket the cells' (:func:`grid_volume`)."""
    coarse = grid_volume(mask, spacing, unit)
    if sub <= 1:
        return coarse
    mask = np.asarray(mask, bool)
    k = mask.ndim
    fine = mask
    for d in range(k):
        fine = np.repeat(fine, sub, axis=d)
    block = (sub,) * k
    for i, values in inside.items():
        cell = np.unravel_index(int(i), mask.shape)
        fine[tuple(slice(c * sub, (c + 1) * sub) for c in cell)] = \
            np.asarray(values, bool).reshape(block)
    f = grid_volume(fine, np.asarray(spacing, float) / sub, unit)
    return replace(coarse, value=f.value, error=f.error, subsamples=int(sub))


def _boundary_subpoints(masks: Mapping, B: np.ndarray, shape, sub: int
                        ) -> tuple[np.ndarray, np.ndarray]:
    """The boundary cells of any of ``masks`` (flat indices, sorted) and their
    sub-points ((cells × sub^k, k), cell after cell)."""
    edge = np.zeros(shape, bool)
    for m in masks.values():
        edge |= boundary_cells(m)
    cells = np.flatnonzero(edge)
    spacing = (B[:, 1] - B[:, 0]) / np.array(shape, float)
    corner = B[:, 0] + np.array(np.unravel_index(cells, shape)).T * spacing
    off = subcell_offsets(len(shape), sub) * spacing
    return cells, (corner[:, None, :] + off[None]).reshape(-1, len(shape))


def _default_subsamples(subsamples, k: int) -> int:
    if subsamples is None:
        return 4 if k <= 2 else 2
    sub = int(subsamples)
    if sub < 1 or sub != subsamples:
        raise InputError(f"subsamples must be a positive integer, got {subsamples!r}")
    return sub


def sample_volume(inside: np.ndarray, box_volume: float, unit: str) -> Volume:
    """:class:`Volume` from the inside fraction of uniform samples of a box: three
    binomial standard errors."""
    inside = np.asarray(inside, bool)
    N = max(inside.size, 1)
    p = inside.sum() / N
    value = float(p * box_volume)
    error = float(3.0 * math.sqrt(max(p * (1 - p), 1.0 / N) / N) * box_volume)
    return Volume(value, error, value - error, value + error, int(inside.sum()), 0, unit)


def component(mask: np.ndarray, index) -> np.ndarray:
    """The cells of ``mask`` connected to cell ``index`` through shared faces (empty
    when that cell is not in ``mask``)."""
    from scipy import ndimage

    mask = np.asarray(mask, bool)
    if index is None or not mask[tuple(index)]:
        return np.zeros_like(mask)
    labels, _ = ndimage.label(mask, ndimage.generate_binary_structure(mask.ndim, 1))
    return labels == labels[tuple(index)]


def _cylinder(d_r: np.ndarray, d_z: np.ndarray, r_box: float, z_box: float
              ) -> tuple[float, float]:
    """Radius and half height of the largest-volume cylinder avoiding every obstacle
    (an obstacle ``i`` is avoided when ``d_r[i] ≥ r`` or ``d_z[i] ≥ h``), within the box
    (``r ≤ r_box``, ``h ≤ z_box``)."""
    order = np.argsort(d_r)
    d_r, d_z = d_r[order], d_z[order]
    # radius just up to d_r[i]: the obstacles j < i (d_r[j] < r) bound the height
    best, best_rh = -1.0, (0.0, 0.0)
    radii = np.r_[d_r[d_r < r_box], r_box]
    prefix = np.minimum.accumulate(np.r_[z_box, d_z])  # min over the first i obstacles
    for r in np.unique(radii):
        i = int(np.searchsorted(d_r, r, side="left"))  # obstacles with d_r < r
        h = float(prefix[i])
        if r * r * h > best:
            best, best_rh = r * r * h, (float(r), h)
    return best_rh


def inscribed_shapes(mask: np.ndarray, points: np.ndarray, centre: np.ndarray,
                     bounds: np.ndarray, spacing: np.ndarray, units: Sequence[str],
                     coords: Sequence[str], grid: bool) -> Inscribed:
    """:class:`Inscribed` in the samples of ``mask`` centred on ``centre``: the samples
    out of it are obstacles (whole cells on a grid, points otherwise), and so is the
    outside of ``bounds``."""
    out = points[~np.asarray(mask, bool).ravel()]
    half = 0.5 * spacing if grid else np.zeros_like(spacing)
    gap = np.maximum(np.abs(out - centre) - half, 0.0)  # per-axis distance to each cell
    to_box = np.minimum(centre - bounds[:, 0], bounds[:, 1] - centre)
    same_unit = len(set(units)) == 1
    err = float(np.max(spacing))
    cube = np.nan
    if same_unit:
        cube = float(min(gap.max(axis=1).min() if len(gap) else np.inf, to_box.min()))
        cube = max(cube, 0.0)
    k = len(coords)
    ax = coords.index("z") if "z" in coords else k - 1
    radial = [i for i in range(k) if i != ax] if k == 3 else list(range(k))
    radius = half_height = np.nan
    if len({units[i] for i in radial}) == 1:
        d_r = np.sqrt((gap[:, radial] ** 2).sum(axis=1))
        r_box = float(to_box[radial].min())
        if k == 3:
            radius, half_height = _cylinder(d_r, gap[:, ax], r_box, float(to_box[ax]))
        elif k == 2:
            radius = float(min(d_r.min() if len(d_r) else np.inf, r_box))
    if not bool(np.asarray(mask, bool).any()):
        cube, radius, half_height = 0.0, 0.0, 0.0 if k == 3 else np.nan
    return Inscribed(np.asarray(centre, float), cube, radius, half_height, coords[ax], err)


# ============================================================ surfaces
def voxel_surface(mask: np.ndarray, bounds: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boundary of a 3-D grid workspace as a triangle mesh: the exposed faces of its
    cells (a face between a cell in ``mask`` and one out, or the box's outside), two
    triangles each, oriented outwards (counter-clockwise seen from outside).

    Exact for the voxel set: the mesh is closed (each directed edge is matched by its
    reverse; where no two cells touch along an edge only, every edge bounds exactly two
    triangles) and the volume it encloses is the cell count times the cell volume.

    Args:
        mask: (n1, n2, n3) the cells in the workspace; bounds: (3, 2) the box they tile.

    Returns:
        ((V, 3) vertices in the workspace coordinates, shared between faces; (F, 3)
        vertex indices of each triangle).
    """
    mask = np.asarray(mask, bool)
    if mask.ndim != 3:
        raise InputError(f"a workspace surface needs 3 coordinates, got {mask.ndim}")
    B = np.asarray(bounds, float)
    spacing = (B[:, 1] - B[:, 0]) / np.array(mask.shape, float)
    padded = np.pad(mask, 1)
    corners, quads = [], []
    for d in range(3):
        a, b = (d + 1) % 3, (d + 2) % 3
        e = np.eye(3, dtype=int)
        for side in (1, -1):
            shifted = np.roll(padded, -side, axis=d)
            cells = np.argwhere(padded & ~shifted) - 1  # cells with this face exposed
            if not len(cells):
                continue
            base = cells + (e[d] if side == 1 else 0)
            ring = [0, e[a], e[a] + e[b], e[b]] if side == 1 else [0, e[b], e[a] + e[b], e[a]]
            quads.append(np.stack([base + r for r in ring], axis=1))  # (k, 4, 3)
    if not quads:
        return np.zeros((0, 3)), np.zeros((0, 3), int)
    Q = np.concatenate(quads)
    lattice, inverse = np.unique(Q.reshape(-1, 3), axis=0, return_inverse=True)
    idx = inverse.reshape(-1, 4)
    faces = np.concatenate([idx[:, [0, 1, 2]], idx[:, [0, 2, 3]]])
    corners = B[:, 0] + lattice * spacing
    return corners, faces


def mesh_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """Volume enclosed by a closed, outward-oriented triangle mesh (divergence theorem:
    the sum of the signed tetrahedra from the origin)."""
    V = np.asarray(vertices, float)[np.asarray(faces, int)]
    return float(np.einsum("ij,ij->i", V[:, 0], np.cross(V[:, 1], V[:, 2])).sum() / 6.0)


# ============================================================ the coordinates
def default_coordinates(mech) -> tuple[str, ...]:
    """The mechanism's independent coordinates at home (those
    :meth:`Mechanism.complete_pose` accepts, first found in the order x, y, z, roll,
    pitch, yaw: a Delta x, y, z; a 3-RPS z, roll, pitch; a 3-RPR x, z, pitch); with more
    than three (a 6-DOF hexapod), x, y, z: the constant-orientation workspace."""
    from .position import coordinate_plan
    from .solve import CoordinateSystem

    home = mech.home_assembly
    system = CoordinateSystem(mech, home.pose, home.leg_q)
    _, held, _ = coordinate_plan(mech, system, [])
    names = tuple(COORDINATES[k] for k in held)
    return names if len(names) <= MAX_COORDINATES else names[:MAX_COORDINATES]


def _check_coords(coords, allowed: Sequence[str]) -> tuple[str, ...]:
    if isinstance(coords, str):
        coords = (coords,)
    names = tuple(str(c).strip() for c in coords)
    bad = [c for c in names if c not in allowed]
    if bad or not names or len(set(names)) != len(names) or len(names) > MAX_COORDINATES:
        raise InputError(f"a workspace is sampled over 1 to {MAX_COORDINATES} distinct "
                         f"coordinates among {', '.join(allowed)}; got {', '.join(names)}")
    return names


def _bounds(bounds, coords, home: np.ndarray, half: np.ndarray) -> np.ndarray:
    """(k, 2) the box: ``bounds`` (a mapping name → (lo, hi), or one pair per
    coordinate, or a flat list lo1 hi1 lo2 hi2 …), default home ± ``half``."""
    k = len(coords)
    if bounds is None:
        return np.stack([home - half, home + half], axis=1)
    if isinstance(bounds, Mapping):
        unknown = [b for b in bounds if b not in coords]
        if unknown:
            raise InputError(f"bounds given for {unknown}, not among the sampled "
                             f"coordinates {list(coords)}")
        B = np.stack([home - half, home + half], axis=1)
        for name, pair in bounds.items():
            B[coords.index(name)] = np.asarray(pair, float)
    else:
        B = np.asarray(bounds, float)
        if B.shape != (k, 2):
            B = B.reshape(-1)
            if B.size != 2 * k:
                raise InputError(f"bounds: {2 * k} numbers (lo, hi per coordinate) for "
                                 f"{', '.join(coords)}, got {B.size}")
            B = B.reshape(k, 2)
    if not np.all(np.isfinite(B)) or np.any(B[:, 1] <= B[:, 0]):
        raise InputError(f"bounds must be finite with lo < hi for each coordinate, got "
                         f"{B.tolist()}")
    return B


def _units(coords, length_unit: str) -> tuple[str, ...]:
    return tuple("rad" if c in COORDINATES[3:] else length_unit for c in coords)


def _volume_unit(units: Sequence[str]) -> str:
    parts = []
    for u in dict.fromkeys(units):
        p = sum(1 for v in units if v == u)
        parts.append(u if p == 1 else f"{u}^{p}")
    return "·".join(parts)


def _home_cell(axes, bounds, home) -> tuple | None:
    """The grid index of the cell holding ``home`` (None outside the box)."""
    if np.any(home < bounds[:, 0]) or np.any(home > bounds[:, 1]):
        return None
    idx = []
    for a, (lo, hi), h in zip(axes, bounds, home):
        n = len(a)
        idx.append(int(min(max(math.floor((h - lo) / (hi - lo) * n), 0), n - 1)))
    return tuple(idx)


def _samples(bounds, sampling, n, samples, seed):
    """``(axes, shape, points)`` of a grid or of Sobol points."""
    if sampling == "grid":
        axes = grid_axes(bounds, n)
        return axes, tuple(len(a) for a in axes), grid_points(axes)
    if sampling != "sobol":
        raise InputError(f"sampling must be 'grid' or 'sobol', got {sampling!r}")
    from scipy.stats import qmc

    N = int(samples if samples is not None else int(n) ** len(bounds))
    if N < 2:
        raise InputError(f"samples must be at least 2, got {N}")
    u = qmc.Sobol(len(bounds), scramble=True, seed=seed).random(N)
    return (), (N,), bounds[:, 0] + u * (bounds[:, 1] - bounds[:, 0])


# ============================================================ mechanisms
def workspace(mech, coords=None, *, bounds=None, n=30, sampling: str = "grid",
              samples: int | None = None, seed: int = 0, at: Mapping | None = None,
              kinds: Sequence[str] | None = None, threshold: float | None = None,
              centre=None, executor: Executor | None = None, chunk_size: int = 2000,
              progress: bool = False, subsamples: int | None = None, checkpoint=None,
              resume: bool = False) -> Workspace:
    """The workspaces of a mechanism over some of its pose coordinates (module docstring).

    Args:
        mech: A :class:`~pkm_pin.Mechanism` (a :class:`~pkm_pin.linkage.Linkage`'s is
            :func:`linkage_workspace`; both are reached by the ``workspace`` method).
        coords: 1 to 3 of x, y, z, roll, pitch, yaw (default
            :func:`default_coordinates`): positions at a fixed orientation give the
            constant-orientation workspace, angles at a fixed position the orientation
            workspace.
        bounds: The box: ``{name: (lo, hi)}`` or one (lo, hi) per coordinate (default
            home ± the characteristic length, angles ± 0.5 rad).
        n: Grid cells per coordinate (an int or one per coordinate).
        sampling: ``"grid"`` or ``"sobol"`` (``samples`` points, default ``n**k``,
            scrambled with ``seed``).
        at: Values of other pose coordinates ``{name: value}`` (default: those the DOF
            needs held at home; the rest, parasitic motions, are solved for).
        kinds: Among :data:`KINDS` (default all).
        threshold: ``min(LTI, CTI)`` of the transmission workspace (default
            :data:`pkm_pin.transmission.GOOD_LTI`, 0.7).
        centre: Centre of the inscribed shapes (k,) (default home).
        executor, chunk_size, progress: As :func:`pkm_pin.sweep.sweep`.
        subsamples: Sub-points per coordinate of each boundary cell for the refined
            volumes (grid; default 4 for one or two coordinates, 2 for three; 1: the
            cell count alone), evaluated on the sweep engine like the cells.
        checkpoint: An output prefix, or a :class:`pkm_pin.checkpoint.Checkpoint`: the
            cells' results (stage ``cells``) and the boundary sub-points' (stage
            ``refine``) are written chunk by chunk to ``PREFIX.partial.npz``; an
            interrupt writes what is done and raises
            :class:`~pkm_pin.checkpoint.Interrupted`; the file is removed when the
            study ends (unless the Checkpoint was made with ``keep=True``).
        resume: With ``checkpoint`` a prefix: continue the study saved there (the same
            arguments; another study is refused); the result is identical, bit for bit,
            to an uninterrupted run.

    Raises:
        InputError: malformed coordinates, bounds or options; home outside the bounds
            for a connected kind. DependentCoordinates: the coordinates (with ``at``)
            are not independent for this mechanism.
    """
    from .transmission import GOOD_LTI

    t0 = time.perf_counter()
    kinds = _kinds(kinds)
    threshold = GOOD_LTI if threshold is None else float(threshold)
    coords = default_coordinates(mech) if coords is None else _check_coords(coords, COORDINATES)
    at = dict(at or {})
    plan, home, B = _plan_and_box(mech, coords, at, bounds)
    axes, shape, points = _samples(B, sampling, n, samples, seed)
    sub = _default_subsamples(subsamples, len(coords))
    cp = _begin_checkpoint(checkpoint, resume, _study_identity(
        mech, coords, B, n, sampling, samples, seed, at, kinds, threshold, chunk_size, sub),
        len(points), mech.n_actuated)
    method, X = _poses(mech, coords, plan, points, B, seed)
    t1 = time.perf_counter()
    res = _sweep_samples(mech, X, method, "transmission" in kinds, executor, chunk_size,
                         progress, cp and cp.stage("cells"))
    t2 = time.perf_counter()
    values = {key: value.reshape(shape) for key, value in _sweep_values(res).items()}
    home_dof, home_det = mech.home_analysis.dof, _home_det(mech)

    def inside(P: np.ndarray) -> dict:
        """The kinds' pointwise properties at the sub-points (the sweep engine)."""
        Xs = _poses(mech, coords, plan, P, B, seed, method)[1]  # no second probe
        r = _sweep_samples(mech, Xs, method, "transmission" in kinds, executor,
                           chunk_size, False, cp and cp.stage("refine"))
        return _pointwise(_sweep_values(r), kinds, home_dof, home_det, threshold)

    ws = _finish(mech.name, coords, _units(coords, mech.length_unit), B, sampling, axes,
                 shape, points, plan["fixed"], home, values, home_dof, home_det, kinds,
                 threshold, centre, method, t0, t1, t2, len(res.failures), sub,
                 (kinds, inside))
    if cp is not None:
        cp.finish()
    return ws


def _plan_and_box(mech, coords, at: dict, bounds) -> tuple:
    """The pose plan of the coordinates (:func:`_pose_plan`), home's coordinates and the
    box (``bounds``, default ± the characteristic length / ANGLE_HALF_RANGE about home)."""
    plan = _pose_plan(mech, coords, at)
    home = plan["home"][[COORDINATES.index(c) for c in coords]]
    L = mech.characteristic_length
    half = np.array([L if c in COORDINATES[:3] else ANGLE_HALF_RANGE for c in coords])
    return plan, home, _bounds(bounds, coords, home, half)


def _study_identity(mech, coords, B, n, sampling, samples, seed, at, kinds, threshold,
                    chunk_size, sub) -> dict:
    """What identifies a workspace study in its checkpoint (a resume of another study is
    refused)."""
    return {"study": "workspace", "mechanism": mech.name, "coords": list(coords),
            "bounds": B, "n": np.broadcast_to(np.asarray(n), (len(coords),)).tolist(),
            "sampling": sampling, "samples": samples, "seed": seed,
            "at": {k: float(v) for k, v in sorted(at.items())}, "kinds": list(kinds),
            "threshold": threshold, "chunk_size": int(chunk_size), "subsamples": sub}


def _sweep_values(res) -> dict:
    """The per-pose arrays of a sweep the workspace kinds read."""
    return {"ok": res.ok, "singularity": res.singularity, "det": res.det, "lti": res.lti,
            "cti": res.cti, "dof": res.dof}


def _begin_checkpoint(checkpoint, resume: bool, study: dict, N: int, n_actuated: int):
    """The study's :class:`~pkm_pin.checkpoint.Checkpoint` (None without one), its
    identity set (a resume of another study refused) and the folder's free space
    checked: the partial file, its temporary copy and the outputs, before the work."""
    from .checkpoint import checkpoint_of

    cp = checkpoint_of(checkpoint, resume)
    if cp is not None:
        cp.begin(study, need=3 * N * (8 * (8 + n_actuated) + 2))
    return cp


def _kinds(kinds) -> tuple[str, ...]:
    if kinds is None:
        return KINDS
    kinds = (kinds,) if isinstance(kinds, str) else tuple(kinds)
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise InputError(f"workspace kinds are {', '.join(KINDS)}; got {', '.join(kinds)}")
    return tuple(k for k in KINDS if k in kinds or k == "reachable")


def _pose_plan(mech, coords, at: dict) -> dict:
    """The coordinates held or given besides ``coords``, and those solved for."""
    from .position import coordinate_plan, partial_pose
    from .solve import CoordinateSystem, pose_coordinates

    both = [c for c in coords if c in at]
    if both:
        raise InputError(f"at: {both[0]} is a sampled coordinate")
    at = partial_pose(at)
    home_asm = mech.home_assembly
    home = pose_coordinates(home_asm.pose)
    system = CoordinateSystem(mech, home_asm.pose, home_asm.leg_q)
    _, held_rows, _ = coordinate_plan(mech, system, list(coords) + list(at))
    fixed = {**at, **{COORDINATES[k]: float(home[k]) for k in held_rows}}
    solved = [c for c in COORDINATES if c not in coords and c not in fixed]
    return {"home": home, "fixed": fixed, "solved": solved}


def _poses(mech, coords, plan, points, bounds, seed, method=None) -> tuple[str, object]:
    """The samples as full poses (N, 6) when the solved-for coordinates are constant
    over the box (probed, unless ``method`` gives the answer of an earlier probe), else
    as partial poses (a list of mappings)."""
    home, fixed, solved = plan["home"], plan["fixed"], plan["solved"]
    if method is None:
        constant = not solved or _constant(mech, coords, plan, bounds, seed)
        method = "poses" if constant else "completed poses"
    if method == "completed poses":
        return method, [{**{c: float(p[j]) for j, c in enumerate(coords)}, **fixed}
                        for p in points]
    full = np.tile(home, (len(points), 1))
    for name, value in fixed.items():
        full[:, COORDINATES.index(name)] = value
    for j, c in enumerate(coords):
        full[:, COORDINATES.index(c)] = points[:, j]
    return method, full


def _constant(mech, coords, plan, bounds, seed, probes: int = 6) -> bool:
    """Whether the solved-for coordinates keep their home values at ``probes`` seeded
    random points within a tenth of the box's span of home (a Delta's or a planar
    mechanism's orientation; not a 3-RPS's parasitic motions). At least two probes must
    complete."""
    from .position import complete
    from .solve import coordinate_errors

    rng = np.random.default_rng(seed)
    span = bounds[:, 1] - bounds[:, 0]
    home, idx = plan["home"], [COORDINATES.index(c) for c in plan["solved"]]
    mid = home[[COORDINATES.index(c) for c in coords]]
    done = 0
    for _ in range(probes):
        p = mid + (rng.random(len(coords)) - 0.5) * 0.2 * span
        try:
            asm = complete(mech, {**{c: float(v) for c, v in zip(coords, p)}, **plan["fixed"]})
        except PkmError:
            continue
        diff = coordinate_errors(asm.pose, idx, home[idx], mech.characteristic_length)
        if np.any(np.abs(diff) > CONSTANT_COORDINATE_TOL):
            return False
        done += 1
    return done >= 2


def _sweep_samples(mech, X, method, transmission, executor, chunk_size, progress,
                   checkpoint=None):
    """The sweep of the samples (partial poses completed in a serpentine order, each from
    its neighbour, and given back in the samples' order); ``checkpoint``: its stage."""
    from .sweep import serpentine_order

    options = dict(executor=executor, chunk_size=chunk_size, progress=progress,
                   transmission=transmission, checkpoint=checkpoint)
    if method == "poses":
        return mech.sweep(X, **options)
    keys = np.array([[p[c] for c in sorted(p)] for p in X])
    order = serpentine_order(keys)
    return mech.sweep([X[k] for k in order], **options).unordered(order)


def _home_det(mech) -> float:
    """The carried determinant at the home pose (its sign is the home side of the type
    II loci): a one-pose sweep of home."""
    res = mech.sweep([mech.home])
    return float(res.det[0])


def _pointwise(values: Mapping, kinds, home_dof: int, home_det: float, threshold: float
               ) -> dict:
    """Per sample, whether it has each kind's properties (before the connection to
    home): reachable; singularity-free (home DOF, class none, home's sign of the carried
    determinant); transmission (that and ``min(LTI, CTI) ≥ threshold``, the CTI where
    it is defined)."""
    ok, cls, det, lti = values["ok"], values["singularity"], values["det"], values["lti"]
    out = {"reachable": np.asarray(ok, bool)}
    if "singularity-free" not in kinds and "transmission" not in kinds:
        return out
    free = out["reachable"] & (cls == "none") & (values["dof"] == home_dof)
    if np.isfinite(home_det) and home_det != 0:
        free &= np.sign(np.nan_to_num(det, nan=home_det)) == np.sign(home_det)
    out["singularity-free"] = free
    if "transmission" in kinds:
        good = free & (np.nan_to_num(lti, nan=-1.0) >= threshold)
        cti = values.get("cti")
        if cti is not None:  # min(LTI, CTI) where the CTI is defined
            good &= np.isnan(cti) | (cti >= threshold)
        out["transmission"] = good
    return out


def _finish(name, coords, units, B, sampling, axes, shape, points, fixed, home, values,
            home_dof, home_det, kinds, threshold, centre, method, t0, t1, t2,
            failures, sub: int = 1, refine=None) -> Workspace:
    """The masks, volumes and inscribed shapes from the per-sample values; ``refine``
    ``(kinds, inside)``: the kinds whose boundary cells are sub-sampled (``sub`` points
    per coordinate) and ``inside(points) -> {kind: (M,) bool}`` (:func:`_pointwise` at
    those points)."""
    grid = sampling == "grid"
    start = _home_cell(axes, B, home) if grid else None
    if grid and start is None and len(kinds) > 1:
        raise InputError(f"home {np.round(home, 6).tolist()} is outside the bounds "
                         f"{B.tolist()}: the connected workspaces grow from home")
    masks = _pointwise(values, kinds, home_dof, home_det, threshold)
    if grid:  # the parts connected to home
        masks = {kind: m if kind == "reachable" else component(m, start)
                 for kind, m in masks.items()}
    k = len(coords)
    spacing = (B[:, 1] - B[:, 0]) / np.array(shape, float) if grid else \
        (B[:, 1] - B[:, 0]) * len(points) ** (-1.0 / k)
    unit = _volume_unit(units)
    box = float(np.prod(B[:, 1] - B[:, 0]))
    volumes = {kind: grid_volume(m, spacing, unit) if grid else sample_volume(m, box, unit)
               for kind, m in masks.items()}
    if grid and refine is not None and sub > 1:
        refinable = {kind: m for kind, m in masks.items() if kind in refine[0]}
        cells, P = _boundary_subpoints(refinable, B, shape, sub)
        inside = refine[1](P) if len(cells) else {}
        per = sub ** k
        for kind, m in refinable.items():
            edge = boundary_cells(m).ravel()
            sub_in = {int(c): inside[kind][i * per:(i + 1) * per]
                      for i, c in enumerate(cells) if edge[c]}
            volumes[kind] = refined_volume(m, spacing, unit, sub, sub_in)
    c = np.asarray(home if centre is None else centre, float)
    if c.shape != (k,) or not np.all(np.isfinite(c)):
        raise InputError(f"centre must be {k} finite numbers ({', '.join(coords)}), got "
                         f"{np.shape(c)}")
    inscribed = {kind: inscribed_shapes(m, points, c, B, spacing, units, coords, grid)
                 for kind, m in masks.items()}
    t3 = time.perf_counter()
    on_bounds = 0
    if grid:
        edge = np.zeros(shape, bool)
        for d in range(k):
            sl = [slice(None)] * k
            sl[d] = [0, shape[d] - 1]
            edge[tuple(sl)] = True
        on_bounds = int((masks["reachable"] & edge).sum())
    ok = values["ok"]
    counts = {"samples": int(ok.size), "assembled": int(ok.sum()), "failures": int(failures),
              **{kind: int(m.sum()) for kind, m in masks.items()}, "on_bounds": on_bounds}
    timing = {"evaluate": t2 - t1, "masks": t3 - t2, "total": t3 - t0,
              "poses_per_s": ok.size / max(t2 - t1, 1e-12)}
    return Workspace(name, tuple(coords), tuple(units), B, sampling, tuple(axes),
                     tuple(shape), points, dict(fixed), np.asarray(home, float), masks,
                     values, volumes, inscribed, counts, timing, float(threshold), method)


# ============================================================ general linkages
def linkage_workspace(link, coords=None, *, bounds=None, n=30, sampling: str = "grid",
                      samples: int | None = None, seed: int = 0,
                      kinds: Sequence[str] | None = None, threshold: float | None = None,
                      centre=None, max_iter: int = 10, progress: bool = False,
                      subsamples: int | None = None, executor: Executor | None = None,
                      chunk_size: int = 2000, checkpoint=None, resume: bool = False,
                      at: Mapping | None = None) -> Workspace:
    """The reachable, singularity-free and good-transmission workspaces of a general
    linkage (module docstring), on a grid, on the working mode of the reference
    assembly.

    Args:
        link: The :class:`~pkm_pin.linkage.Linkage`.
        coords: The output point's coordinates among x, y, z (inverse kinematics of the
            output: default those it moves along, when the output is a point) or actuated
            joint names (forward kinematics; default the first two when the output is
            not a point); the other actuated values, or output coordinates, stay at the
            reference assembly's.
        bounds, n: As :func:`workspace` (default: the reference ± the characteristic
            length, or the actuated joints' limits / ± π).
        kinds: Among :data:`KINDS` (default all): ``"transmission"`` uses
            :meth:`Linkage.transmission <pkm_pin.linkage.Linkage.transmission>` at each
            cell (``min(LTI, CTI)``).
        threshold: ``min(LTI, CTI)`` of the transmission workspace (default
            :data:`pkm_pin.transmission.GOOD_LTI`, 0.7).
        centre: Of the inscribed shapes (default: the reference).
        max_iter: Newton iterations of each continuation step (a step from a
            neighbour converges in a few; one that does not is halved).
        subsamples: As :func:`workspace` but default 1 (each sub-point costs a
            continuation: 4 makes a 40 × 40 five-bar about 18 times slower), for the
            reachable volume only: a sub-point is
            inside when it is followed (continuation) from the configuration of its
            cell, or of the nearest solved neighbour (diagonals included); the other
            kinds' volumes are cell counts.
        executor, chunk_size: The cells reached are analysed (classes, carried
            determinant, transmission) in chunks of ``chunk_size`` cells, on ``executor``
            when given; the continuation that reaches them is sequential.
        at: Over the output point's coordinates, values of the others (``{"z": …}``:
            a slice; default the reference's), reached from the reference by
            continuation before the slice grows.
        checkpoint, resume: As :func:`workspace`: each chunk of cell analyses is
            recorded (stage ``cells``) and an interrupt writes what is done and raises
            :class:`~pkm_pin.checkpoint.Interrupted`; a resume follows the cells again
            (deterministic, a small part of the time) and analyses only the chunks not
            done; the result is identical, bit for bit, to an uninterrupted run. An
            interrupt before the analyses begin stops at once.
    """
    from .transmission import GOOD_LTI

    if sampling != "grid":
        raise InputError("a linkage's workspace grows from cell to cell: sampling='grid'")
    if int(chunk_size) < 1:
        raise InputError(f"chunk_size must be a positive integer, got {chunk_size}")
    t0 = time.perf_counter()
    kinds = _kinds(kinds)
    threshold = GOOD_LTI if threshold is None else float(threshold)
    ref = link.assemble()
    dom = _linkage_domain(link, ref, coords, bounds, at)
    axes, shape, points = _samples(dom.bounds, "grid", n, None, seed)
    start = _start_cell(axes, dom)
    solve_at = _linkage_solver(link, ref, dom, max_iter)
    follow = _continuation(link, dom, solve_at)
    sub = _default_subsamples(1 if subsamples is None else subsamples, len(dom.coords))
    cp = _begin_checkpoint(checkpoint, resume, _linkage_study(
        link, dom, n, kinds, threshold, max_iter, chunk_size, sub), int(np.prod(shape)),
        len(link.actuated))
    t1 = time.perf_counter()
    Q, home_an, values = _linkage_cells(link, ref, dom, points, shape, start, solve_at,
                                        follow, kinds, progress, executor, int(chunk_size),
                                        cp)
    t2 = time.perf_counter()
    ws = _finish(link.name, dom.coords, dom.units, dom.bounds, "grid", axes, shape, points,
                 dom.fixed, dom.home, values, home_an.dof,
                 _carried_det(home_an, home_an.platform_twists), kinds, threshold,
                 centre, dom.method, t0, t1, t2, int((~values["ok"]).sum()), sub,
                 (("reachable",), lambda P: {"reachable": _followed(P, Q, points, shape,
                                                                     sub, follow)}))
    if cp is not None:
        cp.finish()
    return ws


def _linkage_study(link, dom, n, kinds, threshold, max_iter, chunk_size, sub) -> dict:
    """What identifies a linkage workspace in its checkpoint (a resume of another study
    is refused)."""
    return {"study": "linkage workspace", "mechanism": link.name, "coords": list(dom.coords),
            "bounds": dom.bounds,
            "n": np.broadcast_to(np.asarray(n), (len(dom.coords),)).tolist(),
            "kinds": list(kinds), "threshold": threshold, "max_iter": int(max_iter),
            "chunk_size": int(chunk_size), "subsamples": sub, "at": dom.fixed}


def _start_cell(axes, dom) -> tuple:
    """The cell of the reference, where a linkage's workspace grows from."""
    start = _home_cell(axes, dom.bounds, dom.home)
    if start is None:
        raise InputError(f"the reference {np.round(dom.home, 6).tolist()} is outside the "
                         f"bounds {dom.bounds.tolist()}: a linkage's workspace grows from it")
    return start


def _linkage_cells(link, ref, dom, points, shape, start, solve_at, follow, kinds, progress,
                   executor, chunk_size: int, cp) -> tuple:
    """``(Q, home_an, values)`` of :func:`linkage_workspace`: the cells reached from the
    start cell by continuation ({flat index: q}), the reference's analysis, and the
    cells' analyses (checkpointed in ``cp``'s stage ``cells``)."""
    q_start = _first_configuration(link.model, _on_slice(link, ref, dom), dom.home,
                                   points[np.ravel_multi_index(start, shape)], solve_at,
                                   follow)
    Q = _grow(shape, start, q_start, lambda cell: points[np.ravel_multi_index(cell, shape)],
              follow, progress)
    home_an = link.analyze(ref.q)
    values = _linkage_values(link, Q, shape, len(kinds) > 1, "transmission" in kinds,
                             home_an, executor, chunk_size, cp and cp.stage("cells"))
    return Q, home_an, values


class _LinkageDomain(NamedTuple):
    """What a linkage's workspace is taken over: the coordinates (actuated joints or the
    output point's x, y, z), their indices, the reference's values (``home``), the
    bounds, units, the coordinates held fixed, the method's name, the pose rows of an
    output-point target (None over actuated joints), the reference output point and the
    scale of each coordinate (the continuation's step measure)."""

    coords: tuple
    idx: list
    actuated: bool
    home: np.ndarray
    bounds: np.ndarray
    units: tuple
    fixed: dict
    method: str
    rows: np.ndarray | None
    out_xyz: np.ndarray
    scale: np.ndarray


def _linkage_domain(link, ref, coords, bounds, at=None) -> _LinkageDomain:
    """The :class:`_LinkageDomain` of :func:`linkage_workspace`'s arguments."""
    model = link.model
    out_xyz = ref.output_pose.translation.copy()
    if coords is None:
        coords = _default_linkage_coords(link, ref)
    coords = (coords,) if isinstance(coords, str) else tuple(coords)
    if at and all(c in link.actuated for c in coords):
        raise InputError("at: over actuated joints the other actuated joints are held at "
                         "the reference's values; at gives output coordinates (x, y, z) "
                         "of a workspace over the output point")
    if all(c in link.actuated for c in coords):
        coords = _check_coords(coords, link.actuated)
        idx = [link.actuated.index(c) for c in coords]
        home = ref.q_actuated[idx].copy()
        half = np.array([_half_range(link, c) for c in coords])
        B = _bounds(bounds, coords, home, half) if bounds is not None else \
            np.array([actuated_range(link, c, h) for c, h in zip(coords, home)])
        fixed = {a: float(v) for a, v in zip(link.actuated, ref.q_actuated)
                 if a not in coords}
        return _LinkageDomain(coords, idx, True, home, B,
                              tuple(_unit_of(link, c) for c in coords), fixed,
                              "linkage actuated", None, out_xyz,
                              np.array([_scale_of(link, c) for c in coords]))
    if not model.output_point:
        raise InputError("a linkage's workspace over output coordinates needs a point "
                         "output (--point); give actuated joint names instead")
    coords = _check_coords(coords, COORDINATES[:3])
    idx = [COORDINATES.index(c) for c in coords]
    home = out_xyz[idx]
    for name, value in dict(at or {}).items():
        if name in coords or name not in COORDINATES[:3]:
            raise InputError(f"at: {name} is {'varied' if name in coords else 'not one of'}"
                             f" the output point's coordinates"
                             + ("" if name in coords else " x, y, z"))
        out_xyz[COORDINATES.index(name)] = float(value)
    fixed = {c: float(out_xyz[k]) for k, c in enumerate(COORDINATES[:3]) if c not in coords}
    return _LinkageDomain(coords, idx, False, home,
                          _bounds(bounds, coords, home, np.full(len(coords), model.length)),
                          ("m",) * len(coords), fixed, "linkage output",
                          pose_rows(model, model.kinematics(ref.q)), out_xyz,
                          np.full(len(coords), model.length))


def _linkage_solver(link, ref, dom: _LinkageDomain, max_iter: int):
    """``solve_at(p, q0)``: the tree solver for the coordinates ``p`` of the domain
    (actuated targets, or the output point's position) from ``q0``."""
    from .solve import solve_tree

    model = link.model

    def solve_at(p, q0):
        if dom.actuated:
            targets = ref.q_actuated.copy()
            targets[dom.idx] = p
            return solve_tree(model, q0, targets=targets, max_iter=max_iter)
        xyz = dom.out_xyz.copy()
        xyz[dom.idx] = p
        return solve_tree(model, q0, pose=pin.SE3(np.eye(3), xyz), pose_rows=dom.rows,
                          max_iter=max_iter)

    return solve_at


def _continuation(link, dom: _LinkageDomain, solve_at):
    """``follow(p0, q0, p1)``: the configuration at ``p1`` continued from ``q0`` at
    ``p0`` on the same working mode (:func:`_follow`): a step is accepted when the
    joints move at most :data:`BRANCH_JUMP` times the coordinates (``jump``); a revolute
    whose limits span a full turn is also tried round its limit (``starts``)."""
    model = link.model
    turn = _full_turns(model)  # (nv,) revolutes whose limits span a full turn

    def jump(q0, q1, p0, p1) -> float:
        dq = pin.difference(model.tree, q0, q1)
        dq[turn] = (dq[turn] + np.pi) % (2 * np.pi) - np.pi  # the same posture
        dq = np.abs(dq / model.velocity_units).max()
        dp = np.abs((p1 - p0) / dom.scale).max()
        return float(dq / dp) if dp > 0 else (0.0 if dq <= 1e-9 else np.inf)

    def starts(q0):
        yield q0
        near = turn & (np.abs(q0 - np.clip(q0, model.tree.lowerPositionLimit + TURN_MARGIN,
                                            model.tree.upperPositionLimit - TURN_MARGIN))
                       > 0) if turn.any() else turn
        if near.any():  # round the limit: the same posture on the other side
            q1 = q0.copy()
            q1[near] -= 2 * np.pi * np.sign(q0[near])
            yield q1

    def follow(p0, q0, p1):
        return _follow(solve_at, jump, starts, p0, q0, p1)

    return follow


def _on_slice(link, ref, dom):
    """The reference's assembly moved onto the slice the ``at`` values give (the output
    point's held coordinates), by continuation in :data:`SLICE_STEPS` steps; the
    reference itself when it is on it (or the continuation fails: the start cell is
    then solved from the solver's global starts)."""
    from .solve import solve_tree

    held = ref.output_pose.translation
    if dom.actuated or np.allclose(held, dom.out_xyz, rtol=0.0, atol=1e-12 * dom.scale[0]):
        return ref
    q = ref.q
    for k in range(1, SLICE_STEPS + 1):
        xyz = held + k / SLICE_STEPS * (dom.out_xyz - held)
        xyz[dom.idx] = dom.home
        sol = solve_tree(link.model, q, pose=pin.SE3(np.eye(3), xyz), pose_rows=dom.rows)
        if not sol.converged:
            return ref
        q = sol.q
    return link.assembly_at(q)


#: Steps of the continuation that moves the reference onto a workspace slice (``at``).
SLICE_STEPS = 8


def _first_configuration(model, ref, home, p, solve_at, follow):
    """The start cell's configuration (at ``p``): followed from the reference, else from
    the solver's global starts (the reference, neutral, mid-limits); None if neither."""
    from .solve import iter_tree_starts

    q = follow(home, ref.q, p)
    for q1 in () if q is not None else iter_tree_starts(model, None):
        sol = solve_at(p, q1)
        if sol.converged:
            return sol.q
    return q


def _followed(P: np.ndarray, Q: Mapping, points: np.ndarray, shape, sub: int, follow
              ) -> np.ndarray:
    """Whether each sub-point (sub^k per boundary cell, cell after cell) is reached by
    continuation (``follow``) from its cell's configuration, or from the nearest solved
    cell among its 3^k − 1 neighbours (none: outside)."""
    k, per = len(shape), sub ** len(shape)
    out = np.zeros(len(P), bool)
    steps = np.array(list(np.ndindex(*(3,) * k))) - 1
    steps = steps[np.argsort(np.abs(steps).sum(axis=1), kind="stable")]  # self first
    spacing = (points.max(axis=0) - points.min(axis=0)) / np.maximum(np.array(shape) - 1, 1)
    for b in range(len(P) // per):
        sub_p = P[b * per:(b + 1) * per]
        cell = np.floor((sub_p.mean(axis=0) - points.min(axis=0)) / spacing + 0.5).astype(int)
        for step in steps:
            nb = cell + step
            if np.all((nb >= 0) & (nb < shape)):
                i = int(np.ravel_multi_index(tuple(nb), shape))
                if i in Q:
                    out[b * per:(b + 1) * per] = [follow(points[i], Q[i], p) is not None
                                                  for p in sub_p]
                    break
    return out


def _default_linkage_coords(link, ref) -> tuple[str, ...]:
    """The output point's moving coordinates (at the reference), else the first two
    actuated joints."""
    model = link.model
    if model.output_point:
        rows = pose_rows(model, model.kinematics(ref.q))
        moving = np.linalg.norm(rows[:, 3:], axis=0) > 1e-6
        names = tuple(c for c, m in zip(COORDINATES[:3], moving) if m)
        if names:
            return names
    return tuple(link.actuated[:2])


#: A full-turn revolute (limits spanning 2π) within this of a limit [rad] is also
#: tried from the other side of the turn when a cell is followed (:func:`_follow`).
TURN_MARGIN = 0.5
#: Halvings of a cell step before a full-turn revolute may be taken round (a quarter).
TURN_DEPTH = 2


def _full_turns(model) -> np.ndarray:
    """(nv,) the revolutes with one coordinate whose limits span at least a full turn
    (a posture then has two coordinates near ±π; the limits cut the turn)."""
    tree = model.tree
    out = np.zeros(tree.nv, bool)
    if tree.nq != tree.nv:
        return out
    span = tree.upperPositionLimit - tree.lowerPositionLimit
    for j in tree.joints[1:]:
        if j.nq == 1 and not model.translating[j.idx_v] \
                and span[j.idx_q] >= 2 * np.pi - 1e-9:
            out[j.idx_v] = True
    return out


def _scale_of(link, name: str) -> float:
    """The velocity unit of an actuated joint (1 for radians, L for lengths)."""
    model = link.model
    return float(model.velocity_units[model.tree.joints[model.tree.getJointId(name)].idx_v])


def _is_length(link, name: str) -> bool:
    """Whether an actuated joint's coordinate is a length (a prismatic joint)."""
    model = link.model
    return bool(model.translating[model.tree.joints[model.tree.getJointId(name)].idx_v])


def _unit_of(link, name: str) -> str:
    return "m" if _is_length(link, name) else "rad"


def _half_range(link, name: str) -> float:
    """Half the default range of an actuated joint without finite limits: π for an
    angle; for a length, the size of its loops at the home assembly, at most the
    characteristic length (:func:`pkm_pin.closure_gaps.loop_size`)."""
    if not _is_length(link, name):
        return np.pi
    from .closure_gaps import loop_size

    return loop_size(link.model, link.home_assembly.q, name)


def actuated_range(link, name: str, value: float) -> tuple[float, float]:
    """The default range of the actuated joint ``name`` of a linkage: its position
    limits when finite (and narrower than 1e6 characteristic lengths), else ``value`` ±
    π (an angle) or ± the size of its loops (a length, :func:`_half_range`); the CLI's
    maps and the linkage workspace alike."""
    model = link.model
    joint = model.tree.joints[model.tree.getJointId(name)]
    lo = float(model.tree.lowerPositionLimit[joint.idx_q])
    hi = float(model.tree.upperPositionLimit[joint.idx_q])
    if joint.nq == 1 and np.isfinite([lo, hi]).all() and 0 < hi - lo < 1e6 * model.length:
        return lo, hi
    half = _half_range(link, name)
    return value - half, value + half


#: A cell's configuration is continuous with its neighbour's when the joint-space step
#: (``pin.difference`` over the velocity units: radians, lengths / L, its largest
#: component) is at most this many times the coordinate step (lengths / L, radians):
#: otherwise the step is halved (:func:`_follow`).
BRANCH_JUMP = 10.0
#: Halvings of a cell step before a configuration is accepted as it converges
#: (steps of 1/32 of a cell).
BRANCH_DEPTH = 5


def _follow(solve_at, jump, starts, p0, q0, p1):
    """The configuration at ``p1`` on the branch of ``q0`` (at ``p0``), or None: an
    adaptive continuation along the segment.

    A step (first the whole way) is Newton from the last configuration, accepted when
    its joint-space step is at most :data:`BRANCH_JUMP` times the coordinate step
    (``jump(q, q_new, p, p_new)``); otherwise the step is halved, down to
    ``2**-BRANCH_DEPTH`` of the way, where a converged solve is taken as it is (near a
    type I locus the joints move fast, legitimately); after an accepted step the step
    doubles again. A step that does not converge is halved down to a quarter of the
    way only (the target is most likely out of reach). On steps of at most a quarter of
    the way, Newton also starts from ``starts(q)`` (``q`` with its full-turn revolutes
    near a limit taken round): the path is then checked at least every quarter, so
    that it cannot go round through a type I locus."""
    t, h, q, p = 0.0, 1.0, q0, p0
    h_min, h_turn = 0.5 ** BRANCH_DEPTH, 0.5 ** TURN_DEPTH
    while t < 1.0:
        h = min(h, 1.0 - t)
        p_new = p0 + (t + h) * (p1 - p0) if t + h < 1.0 else p1
        found, converged = None, False
        for s in starts(q) if h <= h_turn else (q,):
            sol = solve_at(p_new, s)
            converged |= sol.converged
            if sol.converged and (h <= h_min or jump(q, sol.q, p, p_new) <= BRANCH_JUMP):
                found = sol.q
                break
        if found is None:
            if h <= (h_min if converged else h_turn):
                return None
            h *= 0.5
            continue
        t, q, p, h = t + h, found, p_new, 2.0 * h
    return q


def _grow(shape, start, q_start, point, follow, progress) -> dict:
    """Solve the cells from ``start`` (configuration ``q_start``; None: not solved)
    outwards on its branch (working mode): each cell is followed from a solved
    neighbour's configuration (``follow(p0, q0, p1)``: continuation, :func:`_follow`),
    one try per neighbour; a cell no neighbour reaches continuously is not on this
    branch. Returns {flat index: q} of the cells solved (the part of the workspace
    connected to ``start`` on its branch)."""
    k = len(shape)
    solved: dict = {}
    tried = np.zeros(shape, np.int8)  # neighbours tried
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=int(np.prod(shape)), unit="cell", desc="workspace", leave=False)

    def accept(cell, q):
        solved[int(np.ravel_multi_index(cell, shape))] = q
        if bar is not None:
            bar.update(1)
        for d in range(k):
            for s in (-1, 1):
                nb = list(cell)
                nb[d] += s
                if 0 <= nb[d] < shape[d] \
                        and int(np.ravel_multi_index(nb, shape)) not in solved:
                    queue.append((tuple(nb), cell, q))

    queue: deque = deque()
    if q_start is not None:
        accept(tuple(start), q_start)
    while queue:
        cell, origin, q0 = queue.popleft()
        if int(np.ravel_multi_index(cell, shape)) in solved or tried[cell] >= 2 * k:
            continue
        tried[cell] += 1
        q = follow(point(origin), q0, point(cell))
        if q is not None:
            accept(cell, q)
    if bar is not None:
        bar.close()
    return solved


def _carried_det(an, P0_world: np.ndarray) -> float:
    """``det(A_n Δ P̃ᵀ)`` of a linkage analysis: actuation wrenches normalised, the
    reference's output twists ``P0_world`` projected on the current twist system (both
    homogenised about the analysis' reference point); nan when not square, 0 when an
    actuator's wrench on the output vanishes (it transmits nothing: ``A`` is singular)."""
    p, L = an.reference_point, an.length
    if an.A.shape[0] != an.output_dof or an.output_dof == 0:
        return np.nan
    A = screws.homogenised_about(an.A, p, L)
    norms = np.linalg.norm(A, axis=1, keepdims=True)
    if not (norms > 0.0).all():
        return 0.0
    A = A / norms
    P = screws.homogenised_about(an.platform_twists, p, L)
    P0 = screws.homogenised_about(P0_world, p, L)
    carried = (P0 @ P.T) @ P
    return float(np.linalg.det(A @ (carried @ screws.DELTA).T))


def _linkage_values(link, Q: dict, shape, analyse: bool, transmission: bool, generic,
                    executor: Executor | None = None, chunk_size: int = 2000, stage=None
                    ) -> dict:
    """The per-cell arrays of a linkage workspace (analyses only with ``analyse``, the
    LTI and CTI of :meth:`Linkage.transmission` with ``transmission``); ``q``: each cell's
    configuration (nan rows where not solved); ``generic``: the reference assembly's
    analysis. The cells reached are analysed in chunks of ``chunk_size`` (in cell order;
    on ``executor`` when given), each recorded in the checkpoint ``stage`` when given
    (the chunks it holds already are not analysed again)."""
    N, nq = int(np.prod(shape)), link.model.nq
    cells = np.array(sorted(Q), dtype=np.int64)
    qs = np.array([Q[int(i)] for i in cells], dtype=float).reshape(len(cells), nq)
    chunks = [np.arange(a, min(a + chunk_size, len(cells)))
              for a in range(0, len(cells), chunk_size)]
    parts: list = [None] * len(chunks)
    if stage is not None:
        parts = stage.begin(np.hstack([cells[:, None].astype(float), qs]), chunks,
                            {"analyse": analyse, "transmission": transmission},
                            _cells_unanalysed(len(cells)))
    todo = [k for k, p in enumerate(parts) if p is None]
    with recording(stage):
        if executor is None:
            for k in todo:
                parts[k] = _linkage_chunk(link, qs[chunks[k]], analyse, transmission,
                                          generic)
                if stage is not None:
                    stage.record(chunks[k], parts[k])
        else:
            futures = {executor.submit(_linkage_chunk, link, qs[chunks[k]], analyse,
                                       transmission, generic): k for k in todo}
            for f in as_completed(futures):
                k = futures[f]
                parts[k] = f.result()
                if stage is not None:
                    stage.record(chunks[k], parts[k])
    out = _cells_unanalysed(N)
    for c, part in zip(chunks, parts):
        for key, column in out.items():
            column[cells[c]] = part[key]
    q_all = np.full((N, nq), np.nan)
    q_all[cells] = qs
    out = {key: column.reshape(shape) for key, column in out.items()}
    out["q"] = q_all.reshape(tuple(shape) + (nq,))
    return out


def _cells_unanalysed(M: int) -> dict:
    """The per-cell arrays of M cells not analysed yet (nothing reached)."""
    return {"ok": np.zeros(M, bool), "singularity": np.full(M, "", dtype="<U4"),
            "det": np.full(M, np.nan), "lti": np.full(M, np.nan), "cti": np.full(M, np.nan),
            "dof": np.full(M, -1)}


def _linkage_chunk(link, qs: np.ndarray, analyse: bool, transmission: bool, generic
                   ) -> dict:
    """The per-cell arrays of the configurations ``qs`` of reached cells (a pure task:
    the same result wherever and whenever it runs)."""
    part = _cells_unanalysed(len(qs))
    part["ok"][:] = True
    for i, q in enumerate(qs):
        an = link.analyze(q, generic=generic, nearby=0) if analyse else None
        if transmission:  # from the cell's analysis when made (not made twice)
            tr = link.transmission(q, analysis=an)
            part["lti"][i], part["cti"][i] = tr.lti, tr.cti
        if not analyse:
            part["singularity"][i] = "none"
            part["dof"][i] = generic.dof
            continue
        part["singularity"][i] = an.singularity if not an.constraint_singular else "III"
        part["dof"][i] = an.dof
        part["det"][i] = _carried_det(an, generic.platform_twists)
    part["failures"] = []
    return part


__all__ = ["COORDINATES", "KINDS", "KIND_COLOURS", "Inscribed", "Volume", "Workspace",
           "actuated_range", "boundary_cells", "component", "default_coordinates", "grid_axes",
           "grid_volume",
           "inscribed_shapes", "linkage_workspace", "mesh_volume", "sample_volume",
           "voxel_surface", "workspace"]
