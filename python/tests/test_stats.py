"""Statistical checks: our own χ² of the direction samplers, and the library's suite."""

import numpy as np
import pytest

import brdf_lab
from conftest import direction
from stats_util import chi2_pvalue, hemisphere_bins, hemisphere_counts

N = 1_000_000
BINS = dict(n_cos=8, n_phi=8)


@pytest.mark.parametrize(
    "name, spec, theta",
    [
        ("adaptive", "phong:n=20", 30.0),
        ("adaptive-exact", "ward:alpha_x=0.15,alpha_y=0.4", 50.0),
        ("analytic", "ggx:alpha=0.3", 60.0),
    ],
)
def test_chi2_of_samples_against_the_pdf(name, spec, theta):
    """Histogram of N samples in (cos θ, φ) bins against the bin masses of the sampler's pdf
    (α = 0.01, fixed seed); a pdf 2 % too high on φ > 0 must fail on the same samples."""
    s = brdf_lab.DirectionSampler(name, spec, seed=11, slices=12)
    wo = direction(theta, 10.0)
    wi, pdf, _ = s.sample(wo, N, seed=21)
    counts = hemisphere_counts(wi, **BINS)
    mass, _, _ = hemisphere_bins(s.pdf, wo, sub=16, **BINS)
    below = N - counts.sum()  # samples below the horizon (sphere samplers)
    assert below <= N * (1 - mass.sum()) + 5 * np.sqrt(N) + 5
    assert chi2_pvalue(counts, mass * N) > 0.01

    def broken(wo_, wi_):
        p = s.pdf(wo_, wi_)
        return np.where(wi_[:, 1] > 0, 1.02 * p, p)

    bmass, _, _ = hemisphere_bins(broken, wo, sub=16, **BINS)
    assert chi2_pvalue(counts, bmass / bmass.sum() * counts.sum()) < 0.01


def test_library_validate_passes_and_writes_the_cli_files(tmp_path):
    r = brdf_lab.validate(
        "adaptive", "phong:n=20", theta_o=[30.0], samples=20_000, seed=1,
        json=tmp_path / "v.json", report=tmp_path / "v.md",
    )
    assert r.passed and bool(r)
    assert len(r.tests) > 3 and not r.failures
    assert {t["sampler"] for t in r.tests} == {"adaptive"}
    assert (tmp_path / "v.json").read_text().startswith("{")
    assert (tmp_path / "v.md").stat().st_size > 0


def test_library_validate_catches_its_mutants():
    r = brdf_lab.validate("adaptive", "phong:n=20", theta_o=[30.0], mutants=True)
    assert r.mutants and all(m["detected"] for m in r.mutants)


def test_validate_errors():
    with pytest.raises(ValueError, match="adaptve"):
        brdf_lab.validate("adaptve", "phong")
    # An object without sample(wo, u) and pdf(wo, wi) is refused with the reason (issue 31
    # accepts objects that have them: python/tests/test_byo.py).
    with pytest.raises(TypeError, match=r"sample\(wo, u\) and pdf\(wo, wi\)"):
        brdf_lab.validate(object(), "phong")


def test_study_returns_cells_and_writes_the_cli_files(tmp_path):
    r = brdf_lab.study(
        ["cosine", "analytic"], ["phong:n=20"], theta_o=[30.0], lights=["sky"],
        preset="custom", n_grid=[16, 64], repetitions=4, out=tmp_path,
    )
    brdf_only = [c for c in r.cells if c["estimator"] == "brdf"]
    assert brdf_only and {c["sampler"] for c in brdf_only} == {"cosine", "analytic"}
    # Under a map the study also runs light sampling and MIS (each sampler with each map sampler).
    assert {c["estimator"] for c in r.cells} == {"brdf", "light", "mis-balance", "mis-power"}
    for f in ["results.json", "results.csv", "report.md"]:
        assert (tmp_path / f).stat().st_size > 0
