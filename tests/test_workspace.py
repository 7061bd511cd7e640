"""Workspaces: volumes against closed forms and Monte Carlo, connectivity across type II
loci, inscribed shapes, unit invariance, the CLI's files."""

from __future__ import annotations

import numpy as np
import pytest

import pkm_pin.builders as builders
from pkm_pin.builders import MECHANISMS
from pkm_pin.builders.planar import rpr3_type2_pose
from pkm_pin.errors import InputError
from pkm_pin.workspace import (
    boundary_cells,
    component,
    grid_axes,
    grid_points,
    grid_volume,
    inscribed_shapes,
    mesh_volume,
    refined_volume,
    subcell_offsets,
    voxel_surface,
    workspace,
)

# five-bar of pkm_pin.builders.five_bar(): base pivots at (∓A, 0), links L1, L2
A, L1, L2 = 0.1, 0.2, 0.25
FIVE_BAR_BOX = [(-0.36, 0.36), (-0.46, 0.46)]


def annuli_area(a: float = A, l1: float = L1, l2: float = L2, m: int = 400_001) -> float:
    """Area of the intersection of the annuli |l1 − l2| ≤ |p − (∓a, 0)| ≤ l1 + l2, by
    integration over x of the length of y in both (for y ≥ 0 each annulus is one
    interval [√(r² − dx²), √(R² − dx²)]; doubled by symmetry)."""
    r, R = abs(l1 - l2), l1 + l2
    x = np.linspace(-R + a, R - a, m)

    def interval(dx):
        return (np.sqrt(np.clip(r * r - dx * dx, 0, None)),
                np.sqrt(np.clip(R * R - dx * dx, 0, None)))

    lo1, hi1 = interval(x + a)
    lo2, hi2 = interval(x - a)
    length = 2 * np.clip(np.minimum(hi1, hi2) - np.maximum(lo1, lo2), 0, None)
    return float(np.trapezoid(length, x))


def in_annuli(P: np.ndarray) -> np.ndarray:
    d1, d2 = np.hypot(P[:, 0] + A, P[:, 1]), np.hypot(P[:, 0] - A, P[:, 1])
    r, R = abs(L1 - L2), L1 + L2
    return (d1 >= r) & (d1 <= R) & (d2 >= r) & (d2 <= R)


@pytest.fixture(scope="module")
def five_bar():
    return builders.five_bar().build()


@pytest.fixture(scope="module")
def delta():
    return MECHANISMS["delta"]().build()


DELTA_BOX = np.array([(-0.6, 0.6), (-0.6, 0.6), (-1.3, -0.3)])


def test_annulus_area_formula_is_converged():
    """The reference area does not change when the integration is refined."""
    assert abs(annuli_area(m=400_001) - annuli_area(m=100_001)) < 1e-6


def test_five_bar_reachable_area_is_the_annuli_intersection(five_bar):
    """The five-bar's reachable cells are exactly the cell centres in both annuli, the
    area lies within the stated bound of the closed form at every resolution, the bound
    halves with the cell size and the error at the finest grid is below the coarsest's."""
    exact = annuli_area()
    errors, bounds = [], []
    for n in (10, 20, 40):
        ws = five_bar.workspace(bounds=FIVE_BAR_BOX, n=n, kinds=["reachable"], subsamples=1)
        assert ws.coords == ("x", "y") and ws.method == "linkage output"
        reach, ref = ws.masks["reachable"].ravel(), in_annuli(ws.points)
        assert not (reach & ~ref).any()
        # a cell missed is one that no step from a neighbour reaches on the home working
        # mode without crossing the small holes |p − (∓a, 0)| < l2 − l1 (within a cell)
        missed = ws.points[ref & ~reach]
        near_hole = np.minimum(np.hypot(missed[:, 0] + A, missed[:, 1]),
                               np.hypot(missed[:, 0] - A, missed[:, 1])) - abs(L2 - L1)
        assert len(missed) <= 2 and np.all(near_hole < np.max(ws.spacing))
        v = ws.volumes["reachable"]
        assert v.lower <= exact <= v.upper and abs(v.value - exact) <= v.error
        errors.append(abs(v.value - exact))
        bounds.append(v.error)
    assert bounds[1] < 0.6 * bounds[0] and bounds[2] < 0.6 * bounds[1]
    assert errors[2] < errors[0] and errors[1] < errors[0]


def test_five_bar_singularity_free_part_stops_at_the_type_II_locus(five_bar):
    """The singularity-free area connected to home is a strict part of the reachable
    area; every cell of it has the home sign of the carried determinant."""
    ws = five_bar.workspace(bounds=FIVE_BAR_BOX, n=16)
    free, reach = ws.masks["singularity-free"], ws.masks["reachable"]
    assert free.sum() > 0.3 * reach.sum() and (free & ~reach).sum() == 0
    assert free.sum() < reach.sum()
    det = ws.values["det"][free]
    assert np.all(np.sign(det) == np.sign(det[0]))


def _five_bar_closed_forms(P: np.ndarray):
    """Home working mode (elbows −, +) configurations and LTI = min(|sin γ_i|, |sin ψ|)
    at the points P (nan outside the annuli), by the closed forms."""
    from test_transmission import five_bar_closed_form, five_bar_q

    Q, lti = np.full((len(P), 4), np.nan), np.full(len(P), np.nan)
    for i in np.flatnonzero(in_annuli(P)):
        Q[i] = five_bar_q(P[i])
        iti, oti = five_bar_closed_form(Q[i])
        lti[i] = min(iti.min(), oti)
    return Q, lti


def test_five_bar_transmission_area_is_the_closed_forms_on_the_grid(five_bar):
    """The five-bar's good-transmission cells are those of a brute-force evaluation of
    ITI_i = |sin γ_i|, OTI = |sin ψ| on the same grid (LTI ≥ 0.7, connected to home):
    same cells, same area; the lti values equal the closed forms."""
    ws = five_bar.workspace(bounds=FIVE_BAR_BOX, n=16)
    assert set(ws.masks) == {"reachable", "singularity-free", "transmission"}
    _, lti = _five_bar_closed_forms(ws.points)
    got = ws.values["lti"].ravel()
    reach = ws.masks["reachable"].ravel()
    np.testing.assert_allclose(got[reach], lti[reach], atol=1e-9)
    start = tuple(int(np.argmin(np.abs(a - h))) for a, h in zip(ws.axes, ws.home))
    brute = component((np.nan_to_num(lti, nan=-1) >= 0.7).reshape(ws.shape), start)
    np.testing.assert_array_equal(ws.masks["transmission"], brute)
    area = brute.sum() * np.prod(ws.spacing)
    assert ws.volumes["transmission"].value == pytest.approx(area, rel=1e-12)
    assert 0 < brute.sum() < ws.masks["singularity-free"].sum()
    assert np.all(ws.values["cti"][ws.masks["reachable"]] == 1.0)  # planar: CTI 1
    # the smallest kind of each cell (what the plots and the 3-D view colour)
    codes, kinds = ws.smallest_kind()
    assert kinds == ["reachable", "singularity-free", "transmission"]
    expected = np.where(ws.masks["transmission"], 2,
                        np.where(ws.masks["singularity-free"], 1,
                                 np.where(ws.masks["reachable"], 0, -1)))
    np.testing.assert_array_equal(codes, expected)


def test_five_bar_workspace_keeps_the_home_working_mode(five_bar):
    """Grown cell by cell, the five-bar keeps its elbows' signs (the home working mode)
    over its singularity-free workspace at every resolution: every cell's configuration
    is the closed-form one of that mode, so neighbouring cells' configurations are
    close (a joint moves at most a few times the cell step over L)."""
    for n in (8, 13, 24):
        ws = five_bar.workspace(bounds=FIVE_BAR_BOX, n=n, kinds=["singularity-free"])
        free = ws.masks["singularity-free"]
        q = ws.values["q"]
        assert np.all(np.sin(q[free][:, 1]) < 0) and np.all(np.sin(q[free][:, 3]) > 0)
        ref, _ = _five_bar_closed_forms(ws.points)
        diff = (q.reshape(-1, 4) - ref + np.pi) % (2 * np.pi) - np.pi
        np.testing.assert_allclose(diff[free.ravel()], 0.0, atol=1e-6)
        for d in range(2):  # face neighbours both free
            both = np.logical_and(np.delete(free, -1, axis=d), np.delete(free, 0, axis=d))
            dq = np.diff(q, axis=d)[both]
            dq = np.abs((dq + np.pi) % (2 * np.pi) - np.pi).max()
            assert dq <= 10.0 * ws.spacing[d] / five_bar.model.length


def test_delta_reachable_volume_matches_monte_carlo(delta):
    """The Delta's reachable volume within its joint limits (grid) agrees with a dense
    Monte-Carlo reference (uniform points of the same box, assembled by the sweep) within
    the stated error plus three Monte-Carlo standard errors."""
    ws = delta.workspace(bounds=DELTA_BOX, n=16, kinds=["reachable"])
    assert ws.coords == ("x", "y", "z") and ws.method == "poses"
    rng = np.random.default_rng(7)
    N = 20000
    X = np.zeros((N, 6))
    X[:, :3] = DELTA_BOX[:, 0] + rng.random((N, 3)) * (DELTA_BOX[:, 1] - DELTA_BOX[:, 0])
    ok = delta.sweep(X).ok
    box = float(np.prod(DELTA_BOX[:, 1] - DELTA_BOX[:, 0]))
    p = ok.mean()
    mc, sigma = p * box, np.sqrt(p * (1 - p) / N) * box
    v = ws.volumes["reachable"]
    assert abs(v.value - mc) <= v.error + 3 * sigma
    assert abs(v.value - mc) < 0.05 * mc  # and in fact much closer than the bound
    sobol = delta.workspace(bounds=DELTA_BOX, sampling="sobol", samples=4096,
                            kinds=["reachable"])
    s = sobol.volumes["reachable"]
    assert abs(s.value - mc) <= s.error + 3 * sigma


def test_rpr3_singularity_free_workspace_excludes_its_type_II_pose():
    """At the home orientation, the 3-RPR's singularity-free workspace grown from home
    stops at the known type II pose (a cell centre here, classified II), which is
    reachable: no cell beyond it is in the workspace."""
    mech = MECHANISMS["rpr3"]().build()
    T = rpr3_type2_pose()
    x2, z2 = T.translation[0], T.translation[2]
    hx, hz = 2.0 / 24, 0.6 / 8
    box = [(x2 - 18.5 * hx, x2 + 5.5 * hx), (z2 - 4.5 * hz, z2 + 3.5 * hz)]
    ws = mech.workspace(("x", "z"), bounds=box, n=(24, 8),
                        kinds=["reachable", "singularity-free"])
    assert ws.fixed["pitch"] == pytest.approx(0.6)
    assert ws.axes[0][18] == pytest.approx(x2) and ws.axes[1][4] == pytest.approx(z2)
    assert ws.masks["reachable"][18, 4] and ws.values["singularity"][18, 4] == "II"
    assert not ws.masks["singularity-free"][18, 4]
    free = ws.masks["singularity-free"]
    assert free.sum() > 20
    assert ws.axes[0][free[:, 4]].max() < x2  # home's side of the locus only
    assert ws.masks["reachable"][19:, 4].any()  # though the far side is reachable


def test_component_follows_faces_only():
    """Cells touching only at a corner are not connected; a home cell out of the mask
    gives an empty component."""
    m = np.zeros((4, 4), bool)
    m[0, 0] = m[1, 1] = m[1, 2] = True
    assert component(m, (1, 1)).sum() == 2
    assert component(m, (0, 0)).sum() == 1
    assert component(m, (3, 3)).sum() == 0


def test_grid_volume_brackets_a_ball():
    """A ball's volume lies in the bracket of its grid count at two resolutions; the
    bound falls like the cell size."""
    errs = []
    for n in (20, 40):
        B = np.array([(-1.0, 1.0)] * 3)
        P = grid_points(grid_axes(B, n))
        mask = (np.linalg.norm(P, axis=1) <= 0.8).reshape(n, n, n)
        v = grid_volume(mask, np.full(3, 2.0 / n), "m^3")
        exact = 4 / 3 * np.pi * 0.8 ** 3
        assert v.lower <= exact <= v.upper and abs(v.value - exact) <= v.error
        errs.append(v.error)
    assert errs[1] < 0.6 * errs[0]


def test_inscribed_cube_and_cylinder_in_a_ball():
    """In a ball of radius R: cube half side R/√3, the largest cylinder (axis z) radius
    R√(2/3) and half height R/√3, each within one cell; in a disc, square R/√2 and
    disc R."""
    R, n = 0.8, 60
    B = np.array([(-1.0, 1.0)] * 3)
    P = grid_points(grid_axes(B, n))
    mask = (np.linalg.norm(P, axis=1) <= R).reshape(n, n, n)
    h = np.full(3, 2.0 / n)
    s = inscribed_shapes(mask, P, np.zeros(3), B, h, ("m",) * 3, ("x", "y", "z"), True)
    assert abs(s.cube - R / np.sqrt(3)) <= s.error
    assert abs(s.cylinder_radius - R * np.sqrt(2 / 3)) <= 2 * s.error
    assert abs(s.cylinder_half_height - R / np.sqrt(3)) <= 2 * s.error
    P2 = grid_points(grid_axes(B[:2], n))
    disc = (np.linalg.norm(P2, axis=1) <= R).reshape(n, n)
    s2 = inscribed_shapes(disc, P2, np.zeros(2), B[:2], h[:2], ("m", "m"), ("x", "y"), True)
    assert abs(s2.cube - R / np.sqrt(2)) <= s2.error
    assert abs(s2.cylinder_radius - R) <= s2.error


def test_inscribed_shapes_in_a_box_are_exact():
    """A box-shaped workspace aligned with the cells holds a cube of its smallest half
    side and a cylinder bounded by the box; mixed units give no cube."""
    n = 20
    B = np.array([(-1.0, 1.0)] * 3)
    P = grid_points(grid_axes(B, n))
    inside = (np.abs(P[:, 0]) < 0.5) & (np.abs(P[:, 1]) < 0.7) & (np.abs(P[:, 2]) < 0.9)
    s = inscribed_shapes(inside.reshape(n, n, n), P, np.zeros(3), B, np.full(3, 0.1),
                         ("m",) * 3, ("x", "y", "z"), True)
    assert s.cube == pytest.approx(0.5)
    assert s.cylinder_radius == pytest.approx(0.5) and s.cylinder_half_height == \
        pytest.approx(0.9)
    mixed = inscribed_shapes(inside.reshape(n, n, n), P, np.zeros(3), B, np.full(3, 0.1),
                             ("m", "m", "rad"), ("x", "y", "pitch"), True)
    assert np.isnan(mixed.cube) and mixed.cylinder_radius == pytest.approx(0.5)


def _edge_counts(faces: np.ndarray):
    """Directed edge → count, over the triangles."""
    from collections import Counter

    return Counter((int(a), int(b)) for f in faces for a, b in zip(f, np.roll(f, -1)))


def test_voxel_surface_of_a_ball_is_closed_and_encloses_the_cell_volume():
    """A ball's cells (no two touching along an edge only): every edge of the surface
    bounds exactly two triangles, in opposite directions, and the enclosed volume is
    the cell count times the cell volume; the box's faces close it too."""
    n = 12
    B = np.array([(-1.0, 1.0), (0.0, 3.0), (2.0, 2.5)])
    P = grid_points(grid_axes(B, n))
    c = B.mean(axis=1)
    mask = (np.linalg.norm((P - c) / (B[:, 1] - B[:, 0]), axis=1) <= 0.45).reshape(n, n, n)
    mask[:, :, -1] |= mask.any(axis=2)  # reaching the box's top face
    V, F = voxel_surface(mask, B)
    edges = _edge_counts(F)
    assert all(k == 1 and edges.get((b, a)) == 1 for (a, b), k in edges.items())
    cell = np.prod((B[:, 1] - B[:, 0]) / n)
    assert mesh_volume(V, F) == pytest.approx(mask.sum() * cell, rel=1e-12)
    assert np.all((V >= B[:, 0] - 1e-12) & (V <= B[:, 1] + 1e-12))


def test_voxel_surface_of_any_cell_set_is_closed():
    """Random cells (edge-only contacts included): each directed edge is matched by its
    reverse as often, and the enclosed volume is the cells' volume."""
    rng = np.random.default_rng(3)
    mask = rng.random((6, 7, 5)) < 0.45
    B = np.array([(0.0, 0.6), (-1.0, 0.4), (5.0, 5.5)])
    V, F = voxel_surface(mask, B)
    edges = _edge_counts(F)
    assert all(edges.get((b, a)) == k for (a, b), k in edges.items())
    cell = np.prod((B[:, 1] - B[:, 0]) / np.array(mask.shape))
    assert mesh_volume(V, F) == pytest.approx(mask.sum() * cell, rel=1e-12)
    empty = voxel_surface(np.zeros((2, 2, 2), bool), B)
    assert empty[0].shape == (0, 3) and empty[1].shape == (0, 3)


def test_the_browser_view_draws_each_kind_s_surface(delta):
    """view.workspace_cloud of a 3-D workspace holds each kind's surface mesh, closed and
    enclosing that kind's volume."""
    from pkm_pin.view import workspace_cloud

    ws = delta.workspace(bounds=DELTA_BOX, n=6, kinds=["reachable", "singularity-free"])
    rec = workspace_cloud(ws)
    for kind in ws.masks:
        assert rec.node(f"/meshcat/pkm/workspace/{kind}_surface") is not None
        V, F = voxel_surface(ws.masks[kind], ws.bounds)
        assert mesh_volume(V, F) == pytest.approx(ws.volumes[kind].count, rel=1e-9)


def test_volumes_scale_with_units_and_counts_do_not(delta):
    """The Delta in millimetres: the same cells, volumes × 1e9, inscribed sizes × 1e3."""
    mm = MECHANISMS["delta"](scale=1000.0).build()
    a = delta.workspace(bounds=DELTA_BOX, n=10)
    b = mm.workspace(bounds=1000.0 * DELTA_BOX, n=10)
    for kind in a.masks:
        np.testing.assert_array_equal(a.masks[kind], b.masks[kind])
        assert b.volumes[kind].value == pytest.approx(1e9 * a.volumes[kind].value, rel=1e-9)
        assert b.volumes[kind].error == pytest.approx(1e9 * a.volumes[kind].error, rel=1e-9)
        assert b.inscribed[kind].cube == pytest.approx(1e3 * a.inscribed[kind].cube,
                                                       rel=1e-9, abs=1e-9)
    assert a.counts == b.counts


def test_orientation_workspace_of_the_3rps_completes_parasitic_motions():
    """The 3-RPS over roll, pitch at fixed z: poses completed on its motion (parasitic
    x, y, yaw solved for); home's cell is singularity-free."""
    mech = MECHANISMS["rps3"]().build()
    ws = mech.workspace(("roll", "pitch"), n=5, bounds=[(-0.2, 0.2), (-0.2, 0.2)])
    assert ws.method == "completed poses" and "z" in ws.fixed
    assert ws.masks["singularity-free"][2, 2] and ws.units == ("rad", "rad")
    assert ws.volumes["reachable"].unit == "rad^2"


def test_bad_inputs_are_refused(delta):
    """Unknown coordinates, reversed bounds, home outside the box: InputError."""
    with pytest.raises(InputError):
        delta.workspace(("x", "w"))
    with pytest.raises(InputError):
        delta.workspace(bounds=[(1, 0), (0, 1), (0, 1)], n=4)
    with pytest.raises(InputError, match="outside the bounds"):
        workspace(delta, bounds=[(0.5, 0.6), (0.5, 0.6), (-1.0, -0.9)], n=3)


def test_cli_writes_json_plots_and_view(tmp_path, capsys):
    """`pkm-pin workspace` prints the JSON numbers and writes the JSON, npz, PNG and HTML
    files, for a platform mechanism (3-D slices) and the pinned five-bar (2-D)."""
    import json
    from pathlib import Path

    from pkm_pin.cli import main

    out = tmp_path / "delta"
    assert main(["workspace", "delta", "--coords", "x", "y", "z", "--range", "-0.6", "0.6",
                 "-0.6", "0.6", "-1.3", "-0.3", "--n", "6", "--out", str(out), "--json",
                 "--quiet"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data["volumes"]) == {"reachable", "singularity-free", "transmission"}
    assert data["volumes"]["reachable"]["value"] > 0 and data["counts"]["samples"] == 216
    for name in ("delta.json", "delta.npz", "delta_slices.png", "delta.html"):
        assert (tmp_path / name).stat().st_size > 0
    assert "PointCloud" in (tmp_path / "delta.html").read_text() or \
        (tmp_path / "delta.html").stat().st_size > 100_000
    five = Path(__file__).resolve().parents[1] / "models" / "pinned" / "five_bar.toml"
    out = tmp_path / "five"
    assert main(["workspace", str(five), "--n", "8", "--kind", "reachable", "--out",
                 str(out), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "reachable" in text and "volume" in text
    assert "disc r" in text and "cylinder" not in text and "nan" not in text
    for name in ("five.json", "five_workspace.png", "five.html"):
        assert (tmp_path / name).stat().st_size > 0
    assert main(["workspace", "delta", "--coords", "x", "y", "z", "--range", "-0.6", "0.6",
                 "-0.6", "0.6", "-1.3", "-0.3", "--n", "4", "--kind", "reachable", "--out",
                 str(tmp_path / "d4"), "--view", str(tmp_path / "surface.html"),
                 "--quiet"]) == 0
    assert (tmp_path / "surface.html").stat().st_size > 0
    assert not (tmp_path / "d4.html").exists()
    assert main(["workspace", "delta", "--range", "0", "1"]) == 2


def _refined_annuli(n: int, sub: int = 4):
    """The refined area of the annuli on an n × n grid of FIVE_BAR_BOX, the sub-points
    classified by the closed form."""
    B = np.array(FIVE_BAR_BOX)
    h = (B[:, 1] - B[:, 0]) / n
    mask = in_annuli(grid_points(grid_axes(B, n))).reshape(n, n)
    cells = np.flatnonzero(boundary_cells(mask))
    off = subcell_offsets(2, sub) * h
    inside = {int(c): in_annuli(B[:, 0] + np.array(np.unravel_index(c, mask.shape)) * h
                                + off) for c in cells}
    return refined_volume(mask, h, "m^2", sub, inside)


def test_refined_area_error_falls_with_the_resolution():
    """Boundary cells counted by the fraction of a 4 × 4 sub-grid inside: on the
    five-bar's annuli the error falls at n = 10, 20, 40 (where the cell count's does not)
    and stays within the stated error; the bracket is the cells'."""
    exact = annuli_area()
    errors = []
    for n in (10, 20, 40):
        v = _refined_annuli(n)
        assert abs(v.value - exact) <= v.error and v.lower <= v.value <= v.upper
        assert v.subsamples == 4 and v.lower <= exact <= v.upper
        errors.append(abs(v.value - exact))
    assert errors[0] > errors[1] > errors[2] and errors[2] < 1e-4


def test_five_bar_refined_area_follows_the_closed_form(five_bar):
    """The five-bar's workspace sub-samples its boundary cells on the home working mode
    (continuation): the refined area is within the stated error of the closed form and
    closer to it than the cell count at n = 10."""
    exact = annuli_area()
    v = five_bar.workspace(bounds=FIVE_BAR_BOX, n=10, kinds=["reachable"],
                           subsamples=4).volumes[
        "reachable"]
    assert v.subsamples == 4 and abs(v.value - exact) <= v.error
    assert abs(v.value - _refined_annuli(10).value) <= 0.02 * exact


def test_actuated_range_is_the_joint_limits_or_a_turn_or_a_length():
    """The default range of a linkage's actuated joint (the CLI's maps, the linkage
    workspace): its limits when finite, else its value ± π (an angle) or ± L."""
    from linkage_models import five_bar as five_bar_model

    from pkm_pin.linkage import Linkage
    from pkm_pin.workspace import actuated_range

    link = Linkage(five_bar_model())
    tree, L = link.model.tree, link.model.length
    for name in link.actuated:
        joint = tree.joints[tree.getJointId(name)]
        lo = float(tree.lowerPositionLimit[joint.idx_q])
        hi = float(tree.upperPositionLimit[joint.idx_q])
        got = actuated_range(link, name, 0.25)
        if np.isfinite([lo, hi]).all() and 0 < hi - lo < 1e6 * L:
            assert got == (lo, hi)
        else:
            assert got == pytest.approx((0.25 - np.pi, 0.25 + np.pi))
        tree.lowerPositionLimit[joint.idx_q], tree.upperPositionLimit[joint.idx_q] = -0.5, 0.7
        assert actuated_range(link, name, 0.25) == (-0.5, 0.7)
        tree.lowerPositionLimit[joint.idx_q], tree.upperPositionLimit[joint.idx_q] = -np.inf, np.inf
        assert actuated_range(link, name, 0.25) == pytest.approx((0.25 - np.pi, 0.25 + np.pi))
        tree.lowerPositionLimit[joint.idx_q], tree.upperPositionLimit[joint.idx_q] = lo, hi


def test_a_general_workspace_slice_at_a_held_output_coordinate(tmp_path, capsys):
    """The pinned Delta's point (read over its tree) over x, y at z = −0.7 (its reference
    is at z ≈ −0.76): every cell reached holds its output at (x, y, −0.7) to 1e-9, and
    without at the slice is the reference's; at naming a varied coordinate, or with
    actuated coordinates, is refused in a sentence; the CLI's --at gives the same."""
    from pathlib import Path

    from pkm_pin import load_mechanism
    from pkm_pin.cli import main

    path = Path(__file__).resolve().parents[1] / "models" / "pinned" / "delta_point.toml"
    mech = load_mechanism(path)
    assert mech.backend == "general"
    ws = mech.workspace(("x", "y"), at={"z": -0.7}, n=9, kinds=("reachable",))
    ok = ws.masks["reachable"]
    assert ok.sum() > 10 and ws.fixed == {"z": -0.7}
    Q = ws.values["q"][ok]
    points = ws.points.reshape(ok.shape + (2,))[ok]
    for q, p in zip(Q, points):
        xyz = mech.model.kinematics(q).output_placement.translation
        np.testing.assert_allclose(xyz, [p[0], p[1], -0.7], atol=1e-9)
    plain = mech.workspace(("x", "y"), n=9, kinds=("reachable",))
    z_ref = mech.home_assembly.output_pose.translation[2]
    assert plain.fixed["z"] == pytest.approx(z_ref) and abs(z_ref + 0.7) > 0.05
    with pytest.raises(InputError, match="at: x is varied"):
        mech.workspace(("x", "y"), at={"x": 0.1}, n=5)
    with pytest.raises(InputError, match="at: over actuated joints"):
        mech.workspace(tuple(mech.actuated_names[:2]), at={"z": -0.7}, n=5)
    assert main(["workspace", str(path), "--coords", "x", "y", "--at", "z=-0.7", "--n", "9",
                 "--kind", "reachable", "--quiet", "--out", str(tmp_path / "w")]) == 0
    assert "fixed      z=-0.7" in capsys.readouterr().out


def test_summary_names_the_inscribed_shapes_that_apply():
    """The workspace summary's shapes by coordinates: cube and cylinder (3), square and
    disc (2), half length (1); a shape of coordinates in different units (nan) is left
    out, never printed as nan; a size below a billionth of the resolution is 0."""
    from pkm_pin.cli import _inscribed_words
    from pkm_pin.workspace import Inscribed

    def shapes(cube, r, h, k):
        return _inscribed_words(Inscribed(np.zeros(k), cube, r, h, "z", 0.01), k)

    assert shapes(0.2, 0.3, 0.1, 3) == "cube half side 0.2, cylinder r 0.3 h/2 0.1 (± 0.01)"
    assert shapes(1.665e-16, 0.3, np.nan, 2) == "square half side 0, disc r 0.3 (± 0.01)"
    assert shapes(np.nan, np.nan, np.nan, 2) == ""  # x in m, roll in rad
    assert shapes(np.nan, 0.3, 0.1, 3) == "cylinder r 0.3 h/2 0.1 (± 0.01)"
    assert shapes(0.05, 0.05, np.nan, 1) == "half length 0.05 (± 0.01)"


PISTON = """<mujoco model="piston_loop">
  <worldbody>
    <body name="A">
      <joint name="ja" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01"/>
      <body name="arm" pos="1 0 0"><joint name="jarm" axis="0 0 1"/>
        <geom type="sphere" size="0.01"/></body>
      <body name="B">
        <joint name="piston" type="slide" axis="1 0 0"/>
        <geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.005"/>
        <site name="tip"/>
      </body>
    </body>
    <body name="D" pos="0.5 0 0">
      <joint name="jd" axis="0 0 1"/>
      <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.01"/>
      <site name="end" pos="0.2 0 0"/>
    </body>
  </worldbody>
  <equality><connect site1="tip" site2="end"/></equality>
  <actuator><motor joint="piston"/></actuator>
</mujoco>
"""


def test_the_default_range_of_a_piston_without_limits_is_its_loops_size(tmp_path):
    """A piston (slide, no range) in a loop: ja at the origin, the piston's frame 0.7 m
    out at home (closing on D's end, 0.2 m beyond D's joint at 0.5 m); a 1 m arm off the
    loop makes the characteristic length L = 1 exactly. The piston is a length (L = 1
    made it an angle before: ± π, 'rad') and its default range is its value ± the
    loop's size, 0.7 m (the largest distance between the loop's joint origins at home),
    not ± L."""
    from pkm_pin import load_mechanism
    from pkm_pin.workspace import _unit_of, actuated_range

    path = tmp_path / "piston.xml"
    path.write_text(PISTON)
    link = load_mechanism(path, backend="general")
    assert link.model.length == 1.0 and link.model.translating.tolist() == [
        False, False, True, False]
    np.testing.assert_allclose(link.home_assembly.q, [0.0, 0.0, 0.7, 0.0], atol=1e-12)
    assert _unit_of(link, "piston") == "m"
    lo, hi = actuated_range(link, "piston", 0.7)
    assert lo == pytest.approx(0.0, abs=1e-9) and hi == pytest.approx(1.4, abs=1e-9)
    # the default dynamics motion moves it by a tenth of that size, not of L
    from pkm_pin.trajectory import default_motion

    motion = default_motion(link.model, link.home_assembly.q)
    assert motion.amplitude.tolist() == pytest.approx([0.07], abs=1e-9)
