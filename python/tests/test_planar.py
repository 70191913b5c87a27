"""Environment-map and partition samplers."""

import numpy as np
import pytest

import brdf_lab
from conftest import shared_file
from stats_util import chi2_pvalue


def small_map(rng):
    h, w = 32, 64
    img = rng.gamma(0.5, size=(h, w, 3))
    img[5:8, 40:44] *= 200.0  # a small bright light
    return img


@pytest.mark.parametrize("name", ["envmap-adaptive", "envmap-adaptive-paper", "envmap-cdf"])
def test_envmap_shapes_and_pdfs(name, rng):
    s = brdf_lab.EnvMapSampler(name, small_map(rng), seed=1)
    uv, pdf_uv, dirs, pdf_sa = s.sample(rng.random((1000, 2)))
    assert uv.shape == (1000, 2) and dirs.shape == (1000, 3)
    assert pdf_uv.shape == pdf_sa.shape == (1000,)
    np.testing.assert_allclose(s.pdf_uv(uv), pdf_uv, rtol=1e-12)
    np.testing.assert_allclose(s.pdf(dirs), pdf_sa, rtol=1e-9)
    np.testing.assert_allclose(pdf_sa, pdf_uv / (2 * np.pi**2 * np.sin(np.pi * uv[:, 1])), rtol=1e-9)
    r = s.build_report
    assert r["width"] == 64 and r["height"] == 32 and r["bytes_used"] == s.bytes_used > 0
    if name != "envmap-cdf":
        assert r["leaves"] > 0
        with pytest.raises(ValueError, match="not invertible"):
            s.invert(uv)


def test_envmap_cdf_inverts_its_warp(rng):
    s = brdf_lab.EnvMapSampler("envmap-cdf", small_map(rng))
    u = rng.random((500, 2))
    uv = s.sample(u)[0]
    np.testing.assert_allclose(s.invert(uv), u, atol=1e-9)


def test_envmap_errors(rng):
    with pytest.raises(ValueError, match="did you mean"):
        brdf_lab.EnvMapSampler("envmap-adaptve", small_map(rng))
    with pytest.raises(ValueError, match="shape"):
        brdf_lab.EnvMapSampler("envmap-cdf", np.ones((4, 4, 2)))
    with pytest.raises(ValueError):
        brdf_lab.EnvMapSampler("envmap-cdf", "/nonexistent/map.hdr")
    with pytest.raises(ValueError):
        brdf_lab.EnvMapSampler("envmap-cdf", np.full((8, 16), np.nan))


def test_envmap_from_file_and_sky():
    path = shared_file("data/envmaps/studio_small_09_1k.hdr")
    s = brdf_lab.EnvMapSampler("envmap-adaptive", str(path))
    assert s.sample(10)[0].shape == (10, 2)
    sky = brdf_lab.EnvMapSampler("envmap-cdf", "sky")
    assert sky.build_report["width"] == 1024


def test_envmap_same_samples_whatever_the_thread_count(rng):
    s = brdf_lab.EnvMapSampler("envmap-adaptive", small_map(rng), seed=3)
    u = rng.random((3 * brdf_lab.PAR_CHUNK + 5, 2))
    outs = []
    try:
        for t in (1, 2, 3):
            brdf_lab.set_num_threads(t)
            outs.append(s.sample(u, seed=2) + s.sample(20000, seed=4))
    finally:
        brdf_lab.set_num_threads(None)
    for o in outs[1:]:
        for a, b in zip(outs[0], o):
            np.testing.assert_array_equal(a, b)


def density_table():
    y, x = np.mgrid[0:24, 0:32]
    return 0.05 + np.exp(-((x - 20) ** 2 + (y - 6) ** 2) / 18.0) + 0.5 * (x < 5)


@pytest.mark.parametrize("method", ["adaptive", "cdf"])
def test_partition_sampler_chi2(method):
    """χ² of the samples against the table's cell masses (α = 0.01; fixed seed)."""
    d = density_table()
    s = brdf_lab.PartitionSampler(d, domain=(0.0, 0.0, 2.0, 1.0), method=method, seed=1)
    n = 1_000_000
    pts, pdf = s.sample(n, seed=9)
    assert pts.shape == (n, 2)
    np.testing.assert_allclose(s.pdf(pts), pdf, rtol=1e-12)
    cell_area = (2.0 / 32) * (1.0 / 24)
    np.testing.assert_allclose(pdf, d[(pts[:, 1] * 24).astype(int), (pts[:, 0] * 16).astype(int)] / (d.sum() * cell_area), rtol=1e-9)
    # bins of 4 × 4 cells: the cell masses are exact bin masses
    counts, _, _ = np.histogram2d(pts[:, 1], pts[:, 0], bins=[6, 8], range=[[0, 1], [0, 2]])
    blocks = lambda t: t.reshape(6, 4, 8, 4).sum(axis=(1, 3)).ravel()
    assert chi2_pvalue(counts.ravel(), blocks(d) / d.sum() * n) > 0.01
    # the same samples against a table off by 2 % on half the domain fail
    broken = d.copy()
    broken[:, 16:] *= 1.02
    assert chi2_pvalue(counts.ravel(), blocks(broken) / broken.sum() * n) < 0.01
    r = s.build_report
    assert r["method"] == method and r["bytes_used"] > 0


def test_partition_cdf_inverts_and_adaptive_does_not(rng):
    d = density_table()
    c = brdf_lab.PartitionSampler(d, method="cdf")
    u = rng.random((300, 2))
    np.testing.assert_allclose(c.invert(c.sample(u)[0]), u, atol=1e-9)
    a = brdf_lab.PartitionSampler(d, n_max=1.5, max_depth=8)
    with pytest.raises(ValueError, match="not invertible"):
        a.invert(u)
    with pytest.raises(ValueError, match="shape"):
        brdf_lab.PartitionSampler(np.ones(5))
    with pytest.raises(ValueError):
        brdf_lab.PartitionSampler(-np.ones((4, 4)))
    with pytest.raises(ValueError, match="method"):
        brdf_lab.PartitionSampler(d, method="nope")
