"""A small version of python/examples/render_spheres.py's agreement test: a sphere under an
environment map rendered through the brdf_lab plugin and through Mitsuba's native plugin for the
same material agrees within noise (Welch's t of the mean over the sphere at α/2 and per block
and channel with Šidák at α/2, α = 0.01), and the same comparison rejects the plugin's BRDF
scaled by 0.97 and a plugin whose pdf disagrees with its sampling. A synthetic map and the
repository's RGL file: no data outside the repository."""

import sys

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba", reason="Mitsuba 3 is not installed (pip install './python[mitsuba]')")
dr = pytest.importorskip("drjit")
pytest.importorskip("scipy")

from conftest import REPO  # noqa: E402

sys.path.insert(0, str(REPO / "python" / "examples"))
import render_spheres as rs  # noqa: E402

RES, BLOCK, SPP, REPEATS, ALPHA = 16, 4, 128, 6, 0.01


def variant():
    """llvm_ad_rgb; without LLVM the module is skipped (in scalar_rgb Mitsuba calls the Python
    plugin once per lane: 6 × 16 × 16 × 128 paths per configuration would take minutes)."""
    try:
        mi.set_variant("llvm_ad_rgb")
        dr.eval(mi.Float([1.0, 2.0]))
        return "llvm_ad_rgb"
    except Exception as e:  # noqa: BLE001 - no LLVM backend
        pytest.skip(f"no LLVM for Dr.Jit's llvm_ad_rgb (apt-get install libllvm19): {e}")


@pytest.fixture(scope="module")
def env(tmp_path_factory):
    """Mitsuba set up, and a small synthetic map (a sky gradient and a bright warm patch), so the
    GGX cases need no data files."""
    mi_, dr_ = rs.setup_mitsuba(variant())
    h, w = 32, 64
    v = (np.arange(h) + 0.5) / h
    img = np.zeros((h, w, 3), dtype=np.float32)
    img[...] = (0.2 + 1.5 * (1 - v))[:, None, None] * np.array([0.6, 0.8, 1.0])
    img[4:10, 20:30] = [8.0, 6.0, 3.0]
    path = tmp_path_factory.mktemp("map") / "sky.exr"
    mi_.Bitmap(img).write(str(path))
    return mi_, dr_, path


def replicates(mi_, dr_, bsdf, path, seed0):
    scene = mi_.load_dict(rs.scene_dict(mi_, bsdf, path, RES, SPP, "mis"))
    return np.array([rs.render_once(mi_, scene, SPP, seed0 + k) for k in range(REPEATS)])


def compare(env, material, sampler, scale=1.0):
    mi_, dr_, path = env
    native = replicates(mi_, dr_, material.native, path, 1)
    plugin = replicates(mi_, dr_, rs.plugin_bsdf(material, sampler, scale), path, 101)
    return rs.compare_replicates(native, plugin, rs.sphere_mask(RES), BLOCK, ALPHA)


@pytest.mark.parametrize("sampler", ["adaptive-exact", "analytic"])
def test_ggx_plugin_matches_roughconductor(env, sampler):
    r = compare(env, rs.parse_material("ggx", 0.2), sampler)
    assert r["blocks"] >= 4
    assert r["passed"], r


def test_scaled_brdf_is_rejected(env):
    # the plugin's GGX × 0.97 (eval and sample weight; pdf unchanged): 3 % darker everywhere
    r = compare(env, rs.parse_material("ggx", 0.2), "adaptive-exact", scale=0.97)
    assert not r["passed"], r
    assert r["mean_ratio_plugin_over_native"] < 0.99, r


def test_inconsistent_pdf_is_rejected(env, monkeypatch):
    # the plugin's pdf() × 1.2 while sample() is unchanged: MIS then weighs the emitter samples
    # wrongly (measured: 2 % darker, p of the mean 2·10⁻⁵)
    import brdf_lab.mitsuba as plugin

    cls = plugin.BrdfLabBSDF
    good = cls.pdf
    def bad_pdf(self, ctx, si, wo, active=True):
        return good(self, ctx, si, wo, active) * 1.2

    monkeypatch.setattr(cls, "pdf", bad_pdf)
    r = compare(env, rs.parse_material("ggx", 0.2), "adaptive-exact")
    assert not r["passed"], r


def test_rgl_plugin_matches_measured(env):
    f = REPO / "data" / "measured" / "rgl" / "paper_white_rgb.bsdf"  # in the repository
    r = compare(env, rs.parse_material(f"rgl:{f}", 0.2), "adaptive-exact")
    assert r["passed"], r


def test_sphere_mask_is_inside_the_sphere():
    m = rs.sphere_mask(64)
    # the disc of the sphere's image: radius tan(asin(r/D)) / tan(fov/2) of the half-width
    frac = np.tan(np.arcsin(rs.RADIUS / rs.DISTANCE)) / np.tan(np.radians(rs.FOV) / 2)
    assert m.sum() < np.pi * (32 * frac) ** 2 and m.sum() > np.pi * (32 * frac - 1.5) ** 2
    assert m[32, 32] and not m[0, 0]


def test_cli_errors(tmp_path, capsys):
    assert rs.main(["compare", "--map", str(tmp_path / "none.hdr")]) == 2
    assert "not found" in capsys.readouterr().err
    junk = tmp_path / "junk.hdr"
    junk.write_text("not an image")
    args = ["--res", "8", "--spp", "1", "--block", "2", "--out", str(tmp_path / "out")]
    assert rs.main(["compare", "--map", str(junk), *args]) == 2
    err = capsys.readouterr().err
    assert "cannot load the scene" in err and len(err.strip().splitlines()) == 1, err
    assert rs.main(["compare", "--map", str(junk), "--materials", "phong", *args]) == 2
    assert "unknown material" in capsys.readouterr().err
