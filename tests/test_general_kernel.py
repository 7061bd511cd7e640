"""The compiled general analysis (:mod:`pkm_pin.general_kernel`) against the numpy path
of :meth:`pkm_pin.linkage.Linkage.analyze` it replaces (issue 24): at random assembled
configurations of linkages with point, revolute and weld closures, revolute, prismatic
and spherical joints, idle motions, body and point outputs, homogenised about the output
and about the world origin, every field of the :class:`LinkageAnalysis` agrees to 1e-9
(bases compared through the projectors onto their spans, which an SVD may rotate)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from linkage_models import five_bar, four_bar, spherical_rod

from pkm_pin import general_kernel, load_mechanism, screws
from pkm_pin.errors import AssemblyError, SingularityError
from pkm_pin.linkage import Linkage
from pkm_pin.model.closure_model import ClosureModel, from_mechanism
from pkm_pin.model.extended_urdf import read_extended_urdf

ROOT = Path(__file__).resolve().parents[1]
LOOPS = ROOT / "models" / "loops"


def mechanism_tree(name: str):
    """The closure model of a shipped TOML mechanism (legs welded to the platform)."""
    return from_mechanism(load_mechanism(ROOT / "models" / "mechanisms" / f"{name}.toml"))


MODELS = {
    "four_bar_point": lambda: four_bar("point"),
    "four_bar_revolute": lambda: four_bar("revolute"),
    "rpr3": lambda: mechanism_tree("rpr3"),
    "stewart": lambda: mechanism_tree("stewart"),
    "four_bar_two_motors": lambda: four_bar(actuated=("crank", "rocker")),
    "five_bar": lambda: five_bar(),
    "spherical_rod": lambda: spherical_rod(),
    "cassie_knee": lambda: read_extended_urdf(LOOPS / "cassie_knee.urdf"),
    "delta_loops": lambda: read_extended_urdf(LOOPS / "delta_loops.urdf"),
    "ankle": lambda: read_extended_urdf(LOOPS / "ankle.urdf"),
}


def configurations(link: Linkage, count: int = 3, seed: int = 0) -> list:
    """The home assembly and ``count`` assemblies from random guesses near it (every
    coordinate moved up to 0.2 rad, or 0.2 L)."""
    rng = np.random.default_rng(seed)
    model = link.model
    home = link.assemble()
    out = [home.q]
    for _ in range(20 * count):
        dv = rng.uniform(-0.2, 0.2, model.nv) * model.velocity_units
        try:
            out.append(link.assemble(pin.integrate(model.tree, home.q, dv), starts=0).q)
        except AssemblyError:
            continue
        if len(out) > count:
            break
    assert len(out) > count
    return out


def both(link: Linkage, q: np.ndarray, about: str):
    """``(compiled, numpy)`` analyses at ``q``."""
    compiled = link.analyze(q, about=about)
    general_kernel.ENABLED = False
    try:
        reference = link.analyze(q, about=about)
    finally:
        general_kernel.ENABLED = True
    return compiled, reference


def projector(S: np.ndarray, p: np.ndarray, L: float) -> np.ndarray:
    """Orthogonal projector onto the span of the screws ``S`` homogenised about ``p``."""
    H = screws.homogenised_about(S, p, L) if len(S) else np.zeros((0, 6))
    return H.T @ H  # the rows are orthonormal once homogenised


def assert_same(a, b, L: float) -> None:
    assert a.mobility == b.mobility
    assert (a.output_dof, a.translations, a.singularity) == \
        (b.output_dof, b.translations, b.singularity)
    for key, value in b.indices.items():
        assert a.indices[key] == pytest.approx(value, rel=1e-9, abs=1e-9, nan_ok=True), key
    np.testing.assert_allclose(a.reference_point, b.reference_point, atol=1e-12 * L)
    np.testing.assert_allclose(a.A, b.A, atol=1e-9)
    np.testing.assert_allclose(a.B, b.B, atol=1e-9)
    np.testing.assert_array_equal(a.actuated_prismatic, b.actuated_prismatic)
    for name in ("platform_twists", "constraint_wrenches"):
        np.testing.assert_allclose(projector(getattr(a, name), a.reference_point, L),
                                   projector(getattr(b, name), b.reference_point, L),
                                   atol=1e-9, err_msg=name)


def assert_same_velocities(a, b, rng) -> None:
    """The velocity maps of the two analyses agree (or both refuse): inverse velocity of
    a random output twist, forward velocity and passive rates of random actuated rates
    (of those the inverse map gives, under redundant actuation)."""
    t = rng.normal(size=b.output_dof) @ b.platform_twists
    qd = rng.normal(size=b.B.shape[0])
    if b.indices["inverse"] >= b.singular_tol:
        np.testing.assert_allclose(a.inverse_velocity(t), b.inverse_velocity(t), atol=1e-9)
        if len(b.mobility.independent_actuators) < len(qd):
            qd = b.inverse_velocity(t)
    try:
        t = b.forward_velocity(qd)
    except SingularityError:
        with pytest.raises(SingularityError):
            a.forward_velocity(qd)
        return
    np.testing.assert_allclose(a.forward_velocity(qd), t, atol=1e-9)
    np.testing.assert_allclose(a.joint_rates(qd), b.joint_rates(qd), atol=1e-9)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_compiled_analysis_equals_numpy_path(name):
    model = MODELS[name]()
    link = Linkage(model)
    assert general_kernel.layout(model, link._loops) is not None
    rng = np.random.default_rng(1)
    for q in configurations(link):
        for about in ("output", "world"):
            a, b = both(link, q, about)
            assert_same(a, b, model.length)
            assert_same_velocities(a, b, rng)


def test_point_output_and_idle_motions():
    """The rod analysed as a point (its end's translations): one idle spin, described
    in words the same way on both paths."""
    link = Linkage(spherical_rod(), point=True)
    rng = np.random.default_rng(2)
    for q in configurations(link, count=2):
        a, b = both(link, q, "output")
        assert a.idle_dof == 1 and a.mobility.idle_motions[0].startswith("rod spins")
        assert_same(a, b, link.model.length)
        assert_same_velocities(a, b, rng)


def test_open_chain_without_closures():
    """A tree without closures (no closure rows): the null space is every motion."""
    model = ClosureModel(four_bar().tree, (), ("crank", "coupler"), "coupler_end")
    link = Linkage(model)
    rng = np.random.default_rng(3)
    for q in rng.uniform(-1.0, 1.0, (3, model.nq)):
        a, b = both(link, q, "output")
        assert (a.dof, a.idle_dof, a.output_dof) == (3, 1, 2)  # the rocker spins idle
        assert_same(a, b, model.length)
        assert_same_velocities(a, b, rng)


def test_plain_python_equals_machine_code():
    """Before its machine code is ready the kernel runs as plain Python (one-off calls on
    a fresh installation): the same numbers."""
    link = Linkage(MODELS["cassie_knee"]())
    lay = general_kernel.layout(link.model, link._loops)
    for q in configurations(link, count=1):
        compiled = general_kernel.analyse_pose(lay, q, True, 1e-9)
        plain = general_kernel.analyse_pose.py_func(lay, q, True, 1e-9)
        for x, y in zip(compiled, plain):
            np.testing.assert_allclose(np.asarray(x, float), np.asarray(y, float), atol=1e-12)


def test_numpy_path_where_the_tree_is_not_compiled(monkeypatch):
    """Without a compiled tree (:func:`pkm_pin.tree_kernel.tree_kernel` is None) the
    analysis takes the numpy path and gives the same numbers."""
    link = Linkage(four_bar())
    q = link.assemble().q
    expected = link.analyze(q)
    monkeypatch.setattr(general_kernel, "tree_kernel", lambda model: None)
    general_kernel._LAYOUTS.clear()
    try:
        other = Linkage(four_bar())
        assert general_kernel.layout(other.model, other._loops) is None
        assert_same(other.analyze(q), expected, other.model.length)
    finally:
        general_kernel._LAYOUTS.clear()
