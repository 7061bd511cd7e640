"""Maps of a workspace slice (pkm_pin.plots): files written, Agg only, shapes checked."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from PIL import Image

from pkm_pin import InputError
from pkm_pin.plots import conditioning_map, save_maps, singularity_map


def _slice(n_u: int = 30, n_v: int = 20) -> dict:
    """Synthetic map data: det changes sign on the line u = v; a corner does not assemble."""
    u, v = np.linspace(-1, 1, n_u), np.linspace(-1, 1, n_v)
    V, U = np.meshgrid(v, u, indexing="ij")
    ok = U ** 2 + V ** 2 < 1.6
    det = np.where(ok, U - V, np.nan)
    type_I = np.where(ok, 0.1 * np.abs(U), np.nan)
    cond = np.where(ok, 1.0 / np.maximum(np.abs(U - V), 1e-300), np.nan)
    cond[ok & (U == V)] = np.inf
    sing = np.where(ok, "none", "").astype("<U4")
    sing[ok & (np.abs(U - V) < 1e-12)] = "II"
    return {"u": u, "v": v, "ok": ok, "det": det, "type_I": type_I, "type_II": np.abs(det),
            "condition": cond, "singularity": sing, "labels": np.array(["x [m]", "z [m]"])}


def _legend(fig) -> list[str]:
    return [t.get_text() for t in fig.axes[0].get_legend().get_texts()]


def test_singularity_map_draws_the_sign_and_the_loci(tmp_path):
    """The singularity map is an Agg figure with the det = 0 and type I lines in its legend."""
    d = _slice()
    path = tmp_path / "s.png"
    fig = singularity_map(d["u"], d["v"], d["det"], d["ok"], type_I=d["type_I"],
                          singularity=d["singularity"], labels=("x [m]", "z [m]"), path=path)
    assert isinstance(fig.canvas, FigureCanvasAgg)
    legend = _legend(fig)
    assert "type II locus (det = 0)" in legend
    assert any(t.startswith("type I index") for t in legend)
    assert "does not assemble" in legend
    with Image.open(path) as im:
        assert im.format == "PNG" and im.size[0] > 200


def test_conditioning_map_marks_singular_points(tmp_path):
    """Infinite condition numbers are drawn in the 'over' colour and named in the legend."""
    d = _slice(21, 21)  # odd sizes: the grid hits u == v
    fig = conditioning_map(d["u"], d["v"], d["condition"], d["ok"], det=d["det"],
                           path=tmp_path / "c.png")
    assert "singular (inf)" in _legend(fig)
    assert (tmp_path / "c.png").stat().st_size > 1000


def test_save_maps_writes_both_files_from_npz(tmp_path):
    """save_maps reads the map data (as from an .npz) and writes the two PNG files."""
    np.savez(tmp_path / "m.npz", **_slice())
    paths = save_maps(np.load(tmp_path / "m.npz"), tmp_path / "m", title="test")
    assert [p.name for p in paths] == ["m_singularity.png", "m_conditioning.png"]
    assert all(p.stat().st_size > 1000 for p in paths)


def test_maps_without_any_assembled_pose_still_draw(tmp_path):
    """An all-grey slice (nothing assembles) draws without contour errors."""
    d = _slice(5, 4)
    d["ok"][:] = False
    paths = save_maps(d, tmp_path / "empty")
    assert all(p.is_file() for p in paths)


def test_wrong_shapes_are_refused_with_the_expected_shape():
    """An array that does not match (len(v), len(u)) is an InputError naming both shapes."""
    d = _slice(6, 4)
    with pytest.raises(InputError, match=r"det must have shape .* \(4, 6\), got \(6, 4\)"):
        singularity_map(d["u"], d["v"], d["det"].T, d["ok"])


def test_missing_keys_are_named():
    """save_maps names the keys the map data lacks."""
    with pytest.raises(InputError, match="condition"):
        save_maps({"u": [0, 1], "v": [0, 1], "ok": np.ones((2, 2)), "det": np.ones((2, 2))},
                  "x")
