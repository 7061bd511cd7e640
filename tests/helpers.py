"""Helpers shared by several test modules: ``from helpers import ...``.

pytest puts ``tests/`` on ``sys.path`` (the test files are rootdir-relative modules
without an ``__init__.py``), so the test modules import this file by its name. Fixtures
shared by several modules live in ``conftest.py``; plain functions live here.

Everything here is a test oracle or a test input generator, written with numpy and
Pinocchio only where the module that uses it did so before (no helper replaces a
``pkm_pin`` function under test).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin

from pkm_pin.builders import MECHANISMS, serial_chains

#: Repository root and the committed models.
REPO = Path(__file__).resolve().parents[1]
MODELS = REPO / "models"
URDF_DIR = MODELS / "urdf"
MECHANISM_DIR = MODELS / "mechanisms"


# ------------------------------------------------------------------- shipped models
def shipped_mechanisms():
    """A cache of built shipped mechanisms for one test module.

    Returns ``mechanism(name, scale=1.0)``: ``MECHANISMS[name](scale=scale).build()``,
    built once per ``(name, scale)`` and then reused. Each module makes its own cache
    (``mechanism = shipped_mechanisms()`` at module level), so no mechanism object is
    shared between modules.
    """
    cache: dict = {}

    def mechanism(name: str, scale: float = 1.0):
        """Built shipped mechanism ``name`` at ``scale``, cached for the module."""
        key = (name, scale)
        if key not in cache:
            cache[key] = MECHANISMS[name](scale=scale).build()
        return cache[key]

    return mechanism


def serial_model_path(key: str, tmp_path_factory) -> Path:
    """The committed serial-chain URDF ``key`` (see ``SERIAL_MODEL_FILES``), or a freshly
    generated one in a temporary folder if the file is not there yet."""
    path = URDF_DIR / serial_chains.SERIAL_MODEL_FILES[key]
    if path.is_file():
        return path
    return serial_chains.write_serial_models(tmp_path_factory.mktemp("models"))[
        list(serial_chains.SERIAL_MODEL_FILES).index(key)]


# ------------------------------------------------------------------- random inputs
def random_states(leg, n: int, seed: int, qd_max: float = 1.0, qdd_max: float = 1.0):
    """``n`` seeded random states ``(q, qd, qdd)`` of a leg: ``q`` inside the joint
    limits (``leg.random_configuration``), ``qd`` and ``qdd`` uniform in
    ``[-qd_max, qd_max]`` and ``[-qdd_max, qdd_max]``. Drawn in that order from one
    generator, so a given seed always gives the same states."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q = leg.random_configuration(rng)
        yield q, rng.uniform(-qd_max, qd_max, leg.nv), rng.uniform(-qdd_max, qdd_max, leg.nv)


def path_configuration(leg, q, qd, qdd, t: float) -> np.ndarray:
    """``q(t) = integrate(q, qd t + qdd t²/2)``: the configuration at time ``t`` along
    the path with rates ``qd`` and accelerations ``qdd`` at ``q`` (``pin.integrate``)."""
    return pin.integrate(leg.model, q, qd * t + 0.5 * qdd * t * t)


def fd_point(leg, link: str, p, q, qd, qdd, h: float):
    """Central first and second differences, with step ``h``, of the world position of
    the point ``p`` of ``link`` along :func:`path_configuration`: ``(velocity,
    acceleration)``."""
    x = {t: leg.point_position(link, p, path_configuration(leg, q, qd, qdd, t))
         for t in (-h, 0.0, h)}
    return (x[h] - x[-h]) / (2 * h), (x[h] - 2 * x[0.0] + x[-h]) / (h * h)


def random_platform_twist(m, assembly, rng, angle: float, distance: float) -> np.ndarray:
    """A twist of the platform twist system of ``m`` at ``assembly`` with rotation
    ``angle`` and translation ``distance`` (parts absent from the system stay zero)."""
    P = m.analyze(assembly).platform_twists
    c = rng.normal(size=P.shape[0]) @ P
    w, v = c[:3], c[3:]
    nw, nv = np.linalg.norm(w), np.linalg.norm(v)
    return np.r_[w / nw * angle if nw > 1e-9 else 0 * w, v / nv * distance if nv > 1e-9 else v]


# ------------------------------------------------------------------------- oracles
def fd_jacobian(leg, q: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """Central differences of the world tip placement, axis-first (ω; v_O) columns:
    column k is ``log6(tip(q + eps e_k) tip(q - eps e_k)⁻¹) / (2 eps)``, the steps taken
    with ``pin.integrate``."""
    cols = []
    for k in range(leg.nv):
        dq = np.zeros(leg.nv)
        dq[k] = eps
        plus = leg.tip_placement(pin.integrate(leg.model, q, dq))
        minus = leg.tip_placement(pin.integrate(leg.model, q, -dq))
        m = pin.log6(plus * minus.inverse())
        cols.append(np.r_[m.angular, m.linear] / (2 * eps))
    return np.array(cols).T


def screw_rank(S, length: float = 1.0, tol: float = 1e-9, relative_zero: bool = False) -> int:
    """Rank of a screw system by numpy's SVD, independent of :mod:`pkm_pin.screws`.

    Moments divided by ``length``; rows of norm below 1e-12 dropped (below 1e-12 of the
    largest row norm if ``relative_zero``); rows normalised; singular values above
    ``tol`` times the largest counted.
    """
    S = np.asarray(S, dtype=float).reshape(-1, 6).copy()
    S[:, 3:] /= length
    n = np.linalg.norm(S, axis=1)
    zero = 1e-12 * max(n.max(initial=0.0), 1e-300) if relative_zero else 1e-12
    S = S[n > zero]
    if S.shape[0] == 0:
        return 0
    S /= np.linalg.norm(S, axis=1)[:, None]
    sv = np.linalg.svd(S, compute_uv=False)
    return int(np.sum(sv > tol * sv[0]))


def spans_equal(A, B, length: float = 1.0, tol: float = 1e-9,
                relative_zero: bool = False) -> bool:
    """Whether two screw systems span the same space: equal ranks of ``A``, ``B`` and
    of both stacked (:func:`screw_rank` with the same options)."""
    rA = screw_rank(A, length, tol, relative_zero)
    rB = screw_rank(B, length, tol, relative_zero)
    both = np.vstack([np.reshape(A, (-1, 6)), np.reshape(B, (-1, 6))])
    return rA == rB == screw_rank(both, length, tol, relative_zero)


# ------------------------------------------------------------------------ CLI
#: The notice numba's first compilation prints on stderr (pkm_pin.compiling): on a fresh
#: machine it may precede an error line, whichever test runs first.
COMPILE_NOTICE = ("pkm_pin: compiling ", "pkm_pin: compiled in ")


def stderr_lines(err: str) -> list[str]:
    """The lines of a command's stderr, less numba's compile notices."""
    return [line for line in err.strip().splitlines() if not line.startswith(COMPILE_NOTICE)]


def one_error_line(capsys) -> str:
    """The stderr of the last command, checked to be one 'pkm-pin: error:' line (a
    compile notice of a first run aside)."""
    err = capsys.readouterr().err
    lines = stderr_lines(err)
    assert len(lines) == 1, err
    assert lines[0].startswith("pkm-pin: error:")
    return lines[0]
