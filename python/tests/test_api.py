"""Shapes, errors, reproducibility and pdf consistency of the bindings."""

import numpy as np
import pytest

import brdf_lab
from conftest import direction, shared_file

WO = direction(30.0, 20.0)


def test_models_list_parameters_and_ranges():
    models = {m["name"]: m for m in brdf_lab.models()}
    assert "ggx" in models and "ward" in models and "phong" in models
    alpha = [p for p in models["ggx"]["params"] if p["key"] == "alpha"][0]
    assert alpha["min"] < alpha["max"] and alpha["range"].startswith(("[", "("))
    assert isinstance(alpha["doc"], str) and alpha["doc"]
    names = [s["name"] for s in brdf_lab.samplers()]
    assert {"adaptive", "adaptive-exact", "analytic", "envmap-adaptive"} <= set(names)
    opts = brdf_lab.option_names()
    assert "slices" in opts["set"] and "n_max" in opts["set"] and "cdf_slices" in opts["baselines"]


def test_brdf_eval_shapes_and_broadcast(rng):
    b = brdf_lab.Brdf("ggx:alpha=0.3")
    wi = rng.normal(size=(7, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    f = b.eval(WO, wi)
    assert f.shape == (7,) and f.dtype == np.float64
    rgb = b.eval_rgb(WO, wi)
    assert rgb.shape == (7, 3)
    # one (wo, wi) per row gives the same values as the broadcast
    np.testing.assert_allclose(b.eval(np.tile(WO, (7, 1)), wi), f, rtol=1e-15)
    # lists and other dtypes are converted
    np.testing.assert_allclose(b.eval(list(WO), wi.astype(np.float32)), b.eval(WO, wi.astype(np.float32).astype(np.float64)))
    # below the horizon: 0
    assert b.eval(WO, [0.0, 0.0, -1.0])[0] == 0.0
    assert b.spec == "ggx:alpha=0.3" and b.is_isotropic


def test_sample_shapes(rng):
    s = brdf_lab.DirectionSampler("adaptive", "phong:n=20", seed=3, slices=8)
    u = rng.random((50, 2))
    wi, pdf, f = s.sample(WO, u)
    assert wi.shape == (50, 3) and pdf.shape == (50,) and f.shape == (50,)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=1), 1.0, rtol=1e-12)
    wi2, pdf2, frgb = s.sample(np.tile(WO, (50, 1)), u, seed=1, rgb=True)
    assert frgb.shape == (50, 3)
    wi3, _, _ = s.sample(WO, 10)
    assert wi3.shape == (10, 3)
    assert s.pdf(WO, wi).shape == (50,)
    assert s.bytes_used > 0 and s.build_seconds >= 0
    assert isinstance(s.build_report, str) and len(s.build_report) > 20
    # wo below the horizon: zeros
    wi4, pdf4, f4 = s.sample([0.0, 0.0, -1.0], 3)
    assert np.all(wi4 == 0) and np.all(pdf4 == 0) and np.all(f4 == 0)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: brdf_lab.Brdf("ggx:alpha=7"), "outside the allowed range"),
        (lambda: brdf_lab.Brdf("nosuchmodel"), "nosuchmodel"),
        (lambda: brdf_lab.DirectionSampler("adaptve", "ggx"), "did you mean `adaptive`"),
        (lambda: brdf_lab.DirectionSampler("envmap-cdf", "ggx"), "not a direction sampler"),
        (lambda: brdf_lab.DirectionSampler("cosine", "ggx", slicez=3), "unknown option `slicez`"),
        (lambda: brdf_lab.DirectionSampler("adaptive", "ggx", slices=0), "slices"),
        (lambda: brdf_lab.DirectionSampler("analytic", "lafortune"), "analytic"),
        (lambda: brdf_lab.DirectionSampler("cosine", 42), "spec string"),
    ],
)
def test_errors_are_value_errors_with_the_reason(call, message):
    with pytest.raises((ValueError, TypeError), match=message):
        call()


@pytest.fixture(scope="module")
def cosine():
    return brdf_lab.DirectionSampler("cosine", "ggx:alpha=0.3", seed=1)


@pytest.mark.parametrize(
    "args, message",
    [
        ((WO, np.zeros((3, 3))), r"u must have shape \(N, 2\)"),
        ((WO, np.full((3, 2), 1.5)), r"\[0, 1\)"),
        ((WO, np.array([[np.nan, 0.5]])), r"\[0, 1\)"),
        (([np.nan, 0.0, 1.0], np.zeros((1, 2))), "non-finite"),
        ((np.zeros(3), np.zeros((1, 2))), "zero vector"),
        ((np.tile(WO, (4, 1)), np.zeros((3, 2))), "4 rows"),
        ((np.zeros((2, 2, 3)), np.zeros((2, 2))), r"shape \(3,\) or \(N, 3\)"),
        ((WO, -1), "≥ 0"),
    ],
)
def test_sample_input_errors(cosine, args, message):
    with pytest.raises(ValueError, match=message):
        cosine.sample(*args)


def test_pdf_and_eval_input_errors(cosine):
    with pytest.raises(ValueError, match="3 rows and wi has 2"):
        cosine.pdf(np.tile(WO, (3, 1)), np.tile(WO, (2, 1)))
    with pytest.raises(ValueError, match="non-finite"):
        brdf_lab.Brdf("ggx").eval(WO, [[0.0, np.inf, 1.0]])


def test_given_uniforms_drive_a_two_uniform_sampler(cosine, rng):
    """cosine uses exactly two uniforms: the rows of u decide the samples whatever the seed."""
    u = rng.random((100, 2))
    a = cosine.sample(WO, u, seed=1)[0]
    b = cosine.sample(WO, u, seed=99)[0]
    np.testing.assert_array_equal(a, b)
    c = cosine.sample(WO, u[::-1].copy(), seed=1)[0]
    np.testing.assert_array_equal(a[::-1], c)


@pytest.mark.parametrize("name", ["adaptive", "adaptive-exact", "analytic"])
def test_same_seed_same_samples_whatever_the_thread_count(name, rng):
    s = brdf_lab.DirectionSampler(name, "ggx:alpha=0.2", seed=7, slices=12)
    n = 3 * brdf_lab.PAR_CHUNK + 17  # several chunks
    u = rng.random((n, 2))
    outs = []
    try:
        for threads in (1, 2, 3):
            brdf_lab.set_num_threads(threads)
            assert brdf_lab.num_threads() == threads
            outs.append(s.sample(WO, u, seed=5) + s.sample(WO, n, seed=6))
    finally:
        brdf_lab.set_num_threads(None)
    for o in outs[1:]:
        for a, b in zip(outs[0], o):
            np.testing.assert_array_equal(a, b)
    # a fresh sampler with the same seed repeats the default (call-counter) streams
    s2 = brdf_lab.DirectionSampler(name, "ggx:alpha=0.2", seed=7, slices=12)
    s3 = brdf_lab.DirectionSampler(name, "ggx:alpha=0.2", seed=7, slices=12)
    np.testing.assert_array_equal(s2.sample(WO, 1000)[0], s3.sample(WO, 1000)[0])
    # successive calls draw fresh streams
    assert not np.array_equal(s2.sample(WO, 1000)[0], s2.sample(WO, 1000)[0])


@pytest.mark.parametrize(
    "name, spec",
    [
        ("adaptive", "ggx:alpha=0.2"),
        ("adaptive-exact", "ward:alpha_x=0.1,alpha_y=0.3"),
        ("adaptive-mixture", "phong:n=30"),
        ("analytic", "ggx:alpha=0.2"),
        ("cosine", "lambert"),
        ("lobe-sphere", "phong:n=30"),
        ("tabulated-cdf", "phong:n=30"),
    ],
)
def test_sample_pdf_matches_pdf_of_the_sample(name, spec, rng):
    s = brdf_lab.DirectionSampler(name, spec, seed=2, slices=12, cdf_slices=8)
    wo = np.stack([direction(t, p) for t, p in rng.uniform([0, 0], [85, 360], size=(400, 2))])
    wi, pdf, f = s.sample(wo, rng.random((400, 2)))
    ok = pdf > 0
    assert ok.mean() > 0.9
    np.testing.assert_allclose(s.pdf(wo[ok], wi[ok]), pdf[ok], rtol=1e-9)
    b = brdf_lab.Brdf(spec)
    above = ok & (wi[:, 2] > 0)
    np.testing.assert_allclose(f[above], b.eval(wo[above], wi[above]), rtol=1e-12)


@pytest.mark.parametrize("name", ["adaptive-exact", "adaptive", "cosine"])
def test_int_u_batch_path_outputs_follow_their_own_query(name, rng):
    # With an int u every chunk of PAR_CHUNK queries is one sample_eval_batch call, which
    # adaptive-exact serves grouped by interval: each output must still be its own query's
    # (pdf and f at that query's wo), below-horizon queries zeros, rgb f the model's eval_rgb.
    spec = "ggx:alpha=0.2"
    s = brdf_lab.DirectionSampler(name, spec, seed=4, slices=12)
    n = 2 * brdf_lab.PAR_CHUNK + 33
    wo = np.stack([direction(t, p) for t, p in rng.uniform([0, 0], [85, 360], size=(n, 2))])
    wo[::97] = [0.0, 0.0, -1.0]
    wi, pdf, f = s.sample(wo, n, seed=8)
    below = wo[:, 2] <= 0
    assert np.all(pdf[below] == 0) and np.all(f[below] == 0) and np.all(wi[below] == 0)
    ok = pdf > 0
    assert ok[~below].mean() > 0.9
    np.testing.assert_allclose(s.pdf(wo[ok], wi[ok]), pdf[ok], rtol=1e-9)
    b = brdf_lab.Brdf(spec)
    up = ok & (wi[:, 2] > 0)
    np.testing.assert_allclose(f[up], b.eval(wo[up], wi[up]), rtol=1e-9)
    wi2, _, frgb = s.sample(wo, n, seed=8, rgb=True)
    np.testing.assert_array_equal(wi2, wi)
    np.testing.assert_allclose(frgb[up], b.eval_rgb(wo[up], wi[up]), rtol=1e-12)


def test_save_and_load_round_trip(tmp_path, rng):
    s = brdf_lab.DirectionSampler("adaptive", "phong:n=20", seed=4, slices=6)
    assert s.can_save
    path = tmp_path / "phong.set"
    s.save(path)
    t = brdf_lab.DirectionSampler.load(path, seed=4)
    assert t.name == "adaptive" and t.brdf.spec == "phong:n=20"
    wi = s.sample(WO, 200, seed=1)[0]
    np.testing.assert_array_equal(s.pdf(WO, wi), t.pdf(WO, wi))
    np.testing.assert_array_equal(wi, t.sample(WO, 200, seed=1)[0])
    e = brdf_lab.DirectionSampler("cosine", "lambert")
    assert not e.can_save
    with pytest.raises(ValueError, match="cannot be saved"):
        e.save(tmp_path / "x")
    with pytest.raises(OSError):
        brdf_lab.DirectionSampler.load(tmp_path / "missing.set")


def test_rgl_brdf_and_native_sampler():
    path = shared_file("data/measured/rgl/paper_white_rgb.bsdf")
    b = brdf_lab.Brdf(f"rgl:{path}")
    s = brdf_lab.DirectionSampler("rgl-native", b, seed=1)
    wi, pdf, f = s.sample(WO, 500, seed=3)
    ok = pdf > 0
    np.testing.assert_allclose(s.pdf(WO, wi[ok]), pdf[ok], rtol=1e-9)
    assert b.eval_rgb(WO, wi[ok]).shape == (ok.sum(), 3)
