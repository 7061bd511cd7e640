"""The compiled tree solver (pkm_pin.tree_kernel) against the Pinocchio path: the closure
residual and Jacobian of every closure kind equal ClosureModel's at random
configurations of every shipped closed-loop model, the Jacobian equals finite
differences, the integration equals pin.integrate, and solve_tree finds the same
solutions through either driver."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pkm_pin import load_mechanism, solve, tree_kernel
from pkm_pin.linkage import Linkage
from pkm_pin.model.closure_model import Closure, ClosureModel, from_mechanism
from pkm_pin.model.extended_urdf import read_extended_urdf

ROOT = Path(__file__).resolve().parents[1]
FILES = sorted([*(ROOT / "models" / "loops").glob("*.urdf"),
                *(ROOT / "models" / "loops").glob("*.xml"),
                *(ROOT / "tests" / "data" / "gepetto").glob("*/robot.urdf"),
                *(ROOT / "models" / "pinned").glob("*.toml"),
                ROOT / "benchmarks" / "data" / "planar_2dof" / "robot.urdf"])
MECHANISMS = ["stewart", "rpr3", "agile_eye"]  # base-legs-platform trees: welds, free flyer


def _model(name):
    if isinstance(name, str):
        return from_mechanism(load_mechanism(ROOT / "models" / "mechanisms" / f"{name}.toml"))
    return load_mechanism(name).model


def _label(p):
    return p if isinstance(p, str) else str(p.relative_to(ROOT))


MODELS = [*FILES, *MECHANISMS]


@pytest.fixture(scope="module", params=MODELS, ids=_label)
def model(request):
    return _model(request.param)


def random_q(model, rng) -> np.ndarray:
    """A random configuration drawn with ``rng`` (deterministic: Pinocchio's own random
    draws are not seeded): revolutes in [−π, π], prismatics in ±L, any rotation; drawn
    again while a weld's relative rotation is within 0.2 rad of π, where the rotation's
    logarithm is ill-conditioned and two implementations differ by more than rounding."""
    L = model.length
    for _ in range(100):
        q = np.array(pin.neutral(model.tree))
        for j in range(1, model.tree.njoints):
            joint = model.tree.joints[j]
            i = joint.idx_q
            if joint.nq == 1:
                q[i] = (rng.uniform(-np.pi, np.pi) if model.velocity_units[joint.idx_v] == 1.0
                        else rng.uniform(-L, L))
            elif joint.nq == 2:
                a = rng.uniform(-np.pi, np.pi)
                q[i:i + 2] = np.cos(a), np.sin(a)
            elif joint.nq == 4:
                q[i:i + 4] = unit_quaternion(rng)
            elif joint.nq == 7:
                q[i:i + 3] = rng.uniform(-L, L, 3)
                q[i + 3:i + 7] = unit_quaternion(rng)
        if not near_weld_cut_locus(model, q):
            return q
    raise AssertionError("no configuration away from the log's cut locus")


def unit_quaternion(rng) -> np.ndarray:
    """A uniformly random unit quaternion (x, y, z, w)."""
    v = rng.normal(size=4)
    return v / np.linalg.norm(v)


def random_placement(rng) -> pin.SE3:
    """A random placement drawn with ``rng``: any rotation, translation in [−1, 1]³."""
    x, y, z, w = unit_quaternion(rng)
    return pin.SE3(pin.Quaternion(w, x, y, z).matrix(), rng.uniform(-1, 1, 3))


def near_weld_cut_locus(model, q, margin: float = 0.2) -> bool:
    """Whether some weld's relative rotation at ``q`` is within ``margin`` of π."""
    r, slices = model.closure_residual(q), model.closure_slices()
    return any(np.linalg.norm(r[s][:3]) > np.pi - margin
               for c, s in zip(model.closures, slices) if c.kind == "weld")


def compiled_rows(kern, q):
    n = int(kern.rows[-1])
    e, H = np.empty(n), np.empty((n, kern.nv))
    norms, oMo = np.empty(len(kern.ckind)), np.empty((4, 4))
    worst = tree_kernel.closure_rows_compiled(kern, np.asarray(q, float), e, H, norms, oMo)
    return e, H, norms, oMo, worst


def test_every_shipped_model_has_a_kernel(model):
    """Every closed-loop model shipped (revolute, spherical and free-flyer joints; point,
    weld closures) is represented by the compiled kernel."""
    assert tree_kernel.tree_kernel(model) is not None


def test_compiled_rows_equal_the_closure_model(model):
    """Residual, Jacobian, closure norms and output placement equal ClosureModel's
    (Pinocchio) to rounding at random configurations: 1e-12, or 4e-14 per joint on the
    large trees (the two evaluations round differently along a chain of ~100 joints)."""
    kern = tree_kernel.tree_kernel(model)
    tol = max(1e-12, 4e-14 * model.tree.njoints)
    rng = np.random.default_rng(3)
    out = model.tree.getFrameId(model.output)
    data = model.tree.createData()
    for _ in range(5):
        q = random_q(model, rng)
        e, H, norms, oMo, worst = compiled_rows(kern, q)
        assert np.abs(e - model.closure_residual(q)).max(initial=0.0) <= tol
        assert np.abs(H - model.closure_jacobian(q)).max(initial=0.0) <= tol
        assert np.allclose(norms, model.closure_norms(model.closure_residual(q)), rtol=0,
                           atol=tol)
        assert worst == pytest.approx(norms.max(initial=0.0), abs=1e-15)
        pin.framesForwardKinematics(model.tree, data, q)
        assert np.abs(oMo - data.oMf[out].homogeneous).max() <= tol


@pytest.mark.parametrize("kind", ["point", "revolute", "weld"])
@pytest.mark.parametrize("name", ["five_bar", "cassie_knee", "ankle", "delta_loops"])
def test_every_closure_kind_with_placements(name, kind):
    """Each model's closures rewritten as ``kind`` with random constraint placements
    (C_a, C_b away from the frames): compiled rows equal ClosureModel's to 1e-12, also
    near the closed configuration (small rotation logs)."""
    base = load_mechanism(ROOT / "models" / "loops" / f"{name}.urdf").model
    rng = np.random.default_rng(13)
    closures = tuple(Closure(kind, c.frame_a, c.frame_b, random_placement(rng),
                             random_placement(rng), c.name) for c in base.closures)
    model = ClosureModel(base.tree, closures, base.actuated, base.output, length=base.length)
    kern = tree_kernel.tree_kernel(model)
    for _ in range(4):
        q = random_q(model, rng)
        e, H, _, _, _ = compiled_rows(kern, q)
        assert np.abs(e - model.closure_residual(q)).max() <= 1e-12
        assert np.abs(H - model.closure_jacobian(q)).max() <= 1e-12
    same = tuple(Closure(kind, c.frame_a, c.frame_b, c.placement_a, c.placement_b, c.name)
                 for c in base.closures)
    model = ClosureModel(base.tree, same, base.actuated, base.output, length=base.length)
    q = Linkage(base).assemble().q  # closed: every log near zero (the Taylor branches)
    e, H, _, _, _ = compiled_rows(tree_kernel.tree_kernel(model), q)
    assert np.abs(e - model.closure_residual(q)).max() <= 1e-12
    assert np.abs(H - model.closure_jacobian(q)).max() <= 1e-12


def test_compiled_jacobian_equals_finite_differences(model):
    """The compiled Jacobian is the derivative of the compiled residual along
    pin.integrate (central differences)."""
    kern = tree_kernel.tree_kernel(model)
    q = random_q(model, np.random.default_rng(5))
    _, H, _, _, _ = compiled_rows(kern, q)
    eps = 1e-7
    fd = np.empty_like(H)
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = eps
        fd[:, k] = (compiled_rows(kern, pin.integrate(model.tree, q, dv))[0]
                    - compiled_rows(kern, pin.integrate(model.tree, q, -dv))[0]) / (2 * eps)
    assert np.allclose(H, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(H).max()))


def test_integration_equals_pinocchio(model):
    """tree_integrate (run as Python) equals pin.integrate on every joint kind."""
    kern = tree_kernel.tree_kernel(model)
    rng = np.random.default_rng(7)
    q = random_q(model, rng)
    dv = rng.uniform(-0.5, 0.5, model.nv)
    mine = q.copy()
    tree_kernel.tree_integrate(kern.kind, kern.iq, kern.iv, mine, dv)
    assert np.abs(mine - pin.integrate(model.tree, q, dv)).max() <= 1e-12


@pytest.mark.parametrize("name", ["cassie_knee", "delta_loops", "ankle"])
def test_solve_tree_compiled_equals_the_pinocchio_driver(name):
    """solve_tree from the same open start, with and without actuated targets and with a
    mask of unknowns: the same iterations and the same solution to round-off (1e-8)."""
    model = load_mechanism(ROOT / "models" / "loops" / f"{name}.urdf").model
    link = Linkage(model)
    home = link.assemble()
    rng = np.random.default_rng(11)
    v = rng.uniform(-0.05, 0.05, model.nv)
    q0 = pin.integrate(model.tree, home.q, v)
    targets = home.q_actuated + 0.05
    free = np.ones(model.nv, bool)
    free[rng.integers(model.nv)] = False
    for kwargs in ({}, {"targets": targets}, {"free": free}):
        a = solve.solve_tree(model, q0, compiled=False, **kwargs)
        b = solve.solve_tree(model, q0, compiled=True, **kwargs)
        assert a.converged == b.converged and a.iterations == b.iterations
        # Round-off differs between the two paths and grows along the iterations by the
        # conditioning of the steps (1.3e-10 seen on the Cassie knee on one processor,
        # under 1e-10 on another): 1e-8 rad holds on every processor and is still far
        # below any difference of branch or of iteration count.
        assert np.abs(pin.difference(model.tree, a.q, b.q)).max() <= 1e-8
        assert b.residual == pytest.approx(a.residual, abs=1e-12)
        if b.closure_norms is not None:
            assert np.allclose(b.closure_norms, model.closure_norms(model.closure_residual(b.q)),
                               rtol=0, atol=1e-13)
            assert np.allclose(b.output_placement.homogeneous,
                               model.kinematics(b.q).output_placement.homogeneous, atol=1e-13)


def test_five_bar_forward_kinematics_equals_the_pinocchio_path():
    """PlaCo's planar 5-bar: FK warm-started along 20 random targets through the compiled
    solver equals the Pinocchio driver's, target by target."""
    link = load_mechanism(ROOT / "benchmarks" / "data" / "planar_2dof" / "robot.urdf")
    model = link.model
    home = link.assemble(np.zeros(model.nq))
    targets = home.q_actuated + np.random.default_rng(0).uniform(-0.3, 0.3, (20, 2))
    qa, qb = home.q, home.q
    for t in targets:
        a = solve.solve_tree(model, qa, targets=t, tol=1e-10, compiled=False)
        b = solve.solve_tree(model, qb, targets=t, tol=1e-10, compiled=True)
        assert a.converged and b.converged
        assert np.abs(a.q - b.q).max() <= 1e-12
        qa, qb = a.q, b.q
    fk = link.forward_kinematics(targets[-1], qb, starts=0, tol=1e-10)
    assert np.abs(fk.q - qb).max() <= 1e-12
    assert np.linalg.norm(model.closure_residual(fk.q)) <= 1e-10


def test_unbounded_revolutes(tmp_path):
    """Continuous joints (cos, sin coordinates): same rows as Pinocchio, FK through
    either driver to the same configuration."""
    src = ROOT / "models" / "loops"
    text = (src / "five_bar.urdf").read_text().replace('type="revolute"', 'type="continuous"')
    (tmp_path / "five_bar.urdf").write_text(text)
    shutil.copy(src / "five_bar.yaml", tmp_path / "five_bar.yaml")
    model = read_extended_urdf(tmp_path / "five_bar.urdf")
    assert model.nq == 2 * model.nv
    kern = tree_kernel.tree_kernel(model)
    assert kern is not None and set(kern.kind[1:]) == {tree_kernel.UNBOUNDED}
    rng = np.random.default_rng(2)
    q = random_q(model, rng)
    e, H, _, _, _ = compiled_rows(kern, q)
    assert np.abs(e - model.closure_residual(q)).max() <= 1e-12
    assert np.abs(H - model.closure_jacobian(q)).max() <= 1e-12
    link = Linkage(model)
    home = link.assemble()
    t = home.q_actuated + 0.1
    a = solve.solve_tree(model, home.q, targets=t, compiled=False)
    b = solve.solve_tree(model, home.q, targets=t, compiled=True)
    assert a.converged and b.converged
    assert np.abs(pin.difference(model.tree, a.q, b.q)).max() <= 1e-10


def test_mimic_joints_have_no_kernel():
    """Mimic joints (the Delta's parallelograms) are left to the Pinocchio driver."""
    assert tree_kernel.tree_kernel(_model("delta")) is None


def test_unsupported_joint_falls_back_to_pinocchio():
    """A tree with a joint the kernel does not represent (a planar joint) has no kernel;
    solve_tree still solves it through Pinocchio."""
    tree = pin.Model()
    j1 = tree.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "slider")
    tree.addBodyFrame("tip", j1, pin.SE3(np.eye(3), np.array([0.1, 0.0, 0.0])),
                      tree.addJointFrame(j1))
    tree.addFrame(pin.Frame("anchor", 0, 0, pin.SE3(np.eye(3), np.array([0.3, 0.2, 0.0])),
                            pin.FrameType.OP_FRAME))
    model = ClosureModel(tree, (Closure("point", "anchor", "tip", name="pin"),), (), "tip")
    assert tree_kernel.tree_kernel(model) is None
    sol = solve.solve_tree(model, model.reference, compiled=True)
    assert sol.converged and np.linalg.norm(model.closure_residual(sol.q)) <= 1e-12


def test_disabled_kernel_uses_the_pinocchio_driver(monkeypatch):
    """tree_kernel.ENABLED = False: solve_tree does not touch the compiled solver."""
    model = load_mechanism(ROOT / "models" / "loops" / "four_bar.urdf").model
    monkeypatch.setattr(tree_kernel, "ENABLED", False)
    monkeypatch.setattr(tree_kernel, "SOLVE", None)  # would raise if called
    assert solve.solve_tree(model, model.reference).converged


def compiled_pose_rows(model, q, target):
    ep, Hp = np.empty(6), np.empty((6, model.nv))
    tree_kernel.output_pose_rows_compiled(tree_kernel.tree_kernel(model), np.asarray(q, float),
                                          np.ascontiguousarray(target.homogeneous),
                                          model.output_point, ep, Hp)
    return ep, Hp


def test_compiled_pose_rows_equal_pose_error_rows(model):
    """The output pose rows (the output's log6 against a target, a point output's
    position error) equal :func:`pkm_pin.solve.pose_error_rows` (Pinocchio) to 1e-12 at
    a random configuration and target, and their Jacobian is the central difference of
    the compiled error along pin.integrate."""
    rng = np.random.default_rng(13)
    q = random_q(model, rng)
    kin = model.kinematics(q)
    target = kin.output_placement * pin.exp6(pin.Motion(rng.uniform(-0.3, 0.3, 6)))
    ep, Hp = compiled_pose_rows(model, q, target)
    e, H = solve.pose_error_rows(model, kin, target)
    assert np.abs(ep - e).max() <= 1e-12
    assert np.abs(Hp - H).max() <= 1e-12 * max(1.0, np.abs(H).max())
    eps = 1e-7
    fd = np.empty_like(Hp)
    for k in range(model.nv):
        dv = np.zeros(model.nv)
        dv[k] = eps
        fd[:, k] = (compiled_pose_rows(model, pin.integrate(model.tree, q, dv), target)[0]
                    - compiled_pose_rows(model, pin.integrate(model.tree, q, -dv), target)[0]
                    ) / (2 * eps)
    assert np.allclose(Hp, fd, rtol=0, atol=1e-6 * max(1.0, np.abs(Hp).max()))


@pytest.mark.parametrize("path", [ROOT / "models" / "loops" / "five_bar.urdf",
                                  ROOT / "models" / "loops" / "cassie_knee.urdf",
                                  ROOT / "models" / "pinned" / "delta_point.toml"],
                         ids=lambda p: p.name)
def test_solve_tree_with_pose_rows_compiled_equals_the_pinocchio_driver(path):
    """solve_tree to an output pose near home (all six rows, and the rows a lower-mobility
    output can follow, as inverse kinematics chooses them), from the same start: the
    same convergence and, converged, the same iterations and solution (1e-8) through
    either driver; not converged (six rows on a 2-DOF output: a least-squares minimum
    in a flat valley, where rounding moves the iterate along the valley), the same
    remaining error (1e-6 relative)."""
    from pkm_pin.linkage import pose_rows

    link = load_mechanism(path)
    model = link.model
    home = link.home_assembly
    rng = np.random.default_rng(17)
    kin = model.kinematics(home.q)
    target = kin.output_placement * pin.exp6(pin.Motion(0.01 * rng.standard_normal(6)))
    for rows in (None, pose_rows(model, kin)):
        a = solve.solve_tree(model, home.q, pose=target, pose_rows=rows, compiled=False)
        b = solve.solve_tree(model, home.q, pose=target, pose_rows=rows, compiled=True)
        assert a.converged == b.converged
        # the output's own rows are reached (not on the Cassie knee: a random pose's two
        # chosen rows need not lie on its 2-DOF output's motion)
        assert a.converged or rows is None or path.name == "cassie_knee.urdf"
        if not a.converged:
            assert b.residual == pytest.approx(a.residual, rel=1e-6)
            continue
        assert a.iterations == b.iterations
        assert np.abs(pin.difference(model.tree, a.q, b.q)).max() <= 1e-8
        assert b.pose == pytest.approx(a.pose, abs=1e-10)
        assert b.residual == pytest.approx(a.residual, abs=1e-10)


@pytest.mark.parametrize("seed", range(4))
def test_profile_ldl_and_sparse_normal_equations_equal_the_dense_ones(seed):
    """The tree solver's normal equations summed over each row's nonzero columns and
    factored within their profile (:func:`pkm_pin.newton.ldl` given ``first``) give the
    dense sums' and the dense factors' step to the last bit, on a sparse Jacobian
    shaped like a two-legged robot's (two blocks of local loops, columns in between that
    no row touches)."""
    from pkm_pin.newton import ldl, ldl_solve

    rng = np.random.default_rng(seed)
    m, nf = 40, 60
    Hf = np.zeros((m, nf))
    for row in range(m):
        base = rng.integers(0, 25) + (30 if row >= m // 2 else 0)
        cols = base + rng.choice(6, size=rng.integers(2, 6), replace=False)
        Hf[row, cols] = rng.standard_normal(len(cols))
    e = rng.standard_normal(m)
    lam = 1e-3
    N, g, inv, dx = np.empty((nf, nf)), np.empty(nf), np.empty(nf), np.empty(nf)
    assert tree_kernel.newton_step(Hf, e, m, nf, lam, N, g, inv, dx)
    Nd = np.zeros((nf, nf))
    for a in range(nf):
        for b in range(a + 1):
            s = 0.0
            for row in range(m):
                s += Hf[row, a] * Hf[row, b]
            Nd[a, b] = s
        Nd[a, a] += lam
    gd = np.array([sum(Hf[row, a] * e[row] for row in range(m)) for a in range(nf)])
    invd, xd = np.empty(nf), np.empty(nf)
    assert ldl(Nd, nf, invd)
    ldl_solve(Nd, nf, invd, gd, xd)
    xd = -xd
    big = np.abs(xd).max()
    if big > tree_kernel.TREE_MAX_STEP:
        xd *= tree_kernel.TREE_MAX_STEP / big
    assert np.array_equal(dx, xd)
    assert np.array_equal(np.tril(N), np.tril(Nd))
