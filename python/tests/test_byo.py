"""Bring your own sampler (issue 31): Python objects with sample(wo, u) / pdf(wo, wi) on NumPy
batches run brdf_lab's validation suite and studies beside the built-in samplers.

The correct/broken pair: a cos^2 lobe, and its twin whose pdf is 2 % too high where x > 0.5
(reported consistently by sample and pdf, so only the distribution tests can see it), and a
twin that samples another law (cos^3) while reporting the cos^2 pdf. Suite at α = 0.01
(Šidák-corrected per test), fixed seeds.
"""

import numpy as np
import pytest

import brdf_lab


class CosinePower:
    """pdf(wi) = (n + 1)/(2π) cos^n θi; `scale` where x > 0.5; samples cos^`drawn_n`."""

    def __init__(self, name="py-cos2", n=2.0, scale=1.0, drawn_n=None, with_f=False):
        self.name, self.n, self.scale = name, n, scale
        self.drawn_n = n if drawn_n is None else drawn_n
        self.with_f = with_f
        self.sample_calls = 0
        self.pdf_calls = 0

    def sample(self, wo, u):
        self.sample_calls += 1
        assert wo.shape == (3,) and u.ndim == 2 and u.shape[1] == 2
        cos = (1.0 - u[:, 0]) ** (1.0 / (self.drawn_n + 1.0))
        sin = np.sqrt(np.maximum(0.0, 1.0 - cos * cos))
        phi = 2.0 * np.pi * u[:, 1]
        wi = np.stack([sin * np.cos(phi), sin * np.sin(phi), cos], axis=1)
        pdf = self._pdf(wi)
        return (wi, pdf, np.full(len(pdf), 1.0 / np.pi)) if self.with_f else (wi, pdf)

    def pdf(self, wo, wi):
        self.pdf_calls += 1
        return self._pdf(wi)

    def _pdf(self, wi):
        p = (self.n + 1.0) / (2.0 * np.pi) * np.maximum(wi[:, 2], 0.0) ** self.n
        return np.where(wi[:, 0] > 0.5, self.scale * p, p)


def run(sampler, seed=3):
    return brdf_lab.validate(sampler, "phong:n=5", theta_o=[30], samples=20_000, seed=seed)


def test_a_correct_python_sampler_passes_with_batched_draws():
    s = CosinePower(with_f=True)
    r = run(s)
    assert r.passed, r.failures
    tested = {t["test"] for t in r.tests if t["sampler"] == "py-cos2"}
    assert {"chi-square", "ks-cos-theta", "pdf-consistency", "normalisation", "unbiasedness"} <= tested
    # 20 000 one-sample draws in chunks of 4096 plus the batches: far fewer calls than samples.
    assert s.sample_calls < 2_000, s.sample_calls


def test_a_pdf_two_percent_off_in_one_region_fails():
    s = CosinePower(scale=1.02)
    r = run(s)
    assert not r.passed
    failed = {t["test"] for t in r.failures}
    assert "normalisation" in failed and "pdf-consistency" not in failed, failed
    # The suite's quadratures are served level by level from batched pdf calls (no call per
    # point), even at the pdf's jump where they refine deepest.
    assert s.pdf_calls < 500, s.pdf_calls


def test_samples_from_another_law_fail():
    r = run(CosinePower(drawn_n=3.0))
    assert not r.passed
    assert {"chi-square", "ks-cos-theta"} & {t["test"] for t in r.failures}


def test_named_by_a_dict_or_listed_beside_builtin_samplers():
    r = brdf_lab.validate({"mine": CosinePower()}, "lambert", theta_o=[45], samples=5_000, seed=2)
    assert r.passed and {t["sampler"] for t in r.tests} == {"mine"}
    r = brdf_lab.validate(["cosine", CosinePower()], "lambert", theta_o=[45], samples=5_000, seed=2)
    assert r.passed and {t["sampler"] for t in r.tests} == {"cosine", "py-cos2"}


def test_errors_of_the_object_are_raised():
    class Bad(CosinePower):
        def pdf(self, wo, wi):
            raise RuntimeError("no pdf here")

    with pytest.raises(ValueError, match="no pdf here"):
        run(Bad(name="bad"))
    with pytest.raises(ValueError, match="name of its own"):
        run(CosinePower(name="cosine"))
    with pytest.raises(TypeError):
        brdf_lab.validate(object(), "lambert")

    class WrongShape(CosinePower):
        def sample(self, wo, u):
            wi, pdf = super().sample(wo, u)
            return wi[:, :2], pdf

    with pytest.raises(ValueError, match=r"wi must have shape"):
        run(WrongShape(name="shape"))


def test_a_python_sampler_is_studied_beside_builtin_ones():
    s = brdf_lab.study(
        ["cosine", "uniform"],
        "lambert",
        [30],
        "constant",
        preset="custom",
        n_grid=[1, 8],
        repetitions=4,
        variance_samples=500,
        timing_samples=100,
        extra_samplers={"mine": CosinePower()},
    )
    cells = {c["sampler"]: c for c in s.cells}
    assert set(cells) == {"cosine", "uniform", "mine"}
    # Lambert under constant light: the estimator of cos^2 sampling has variance (not ∝ cos),
    # cosine sampling has none.
    assert cells["cosine"]["zero_variance"] and not cells["mine"]["zero_variance"]
    assert cells["mine"]["timing"]["estimator_ns"] > 0
