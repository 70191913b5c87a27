"""A small χ² goodness-of-fit test (Pearson, bins with expected count < 5 pooled)."""

import numpy as np
from scipy import stats


def chi2_pvalue(observed, expected, min_expected=5.0):
    observed = np.asarray(observed, dtype=float).ravel()
    expected = np.asarray(expected, dtype=float).ravel()
    order = np.argsort(expected)
    o, e = observed[order], expected[order]
    # pool the smallest bins until each pooled bin expects ≥ min_expected
    po, pe, acc_o, acc_e = [], [], 0.0, 0.0
    for oi, ei in zip(o, e):
        acc_o += oi
        acc_e += ei
        if acc_e >= min_expected:
            po.append(acc_o)
            pe.append(acc_e)
            acc_o = acc_e = 0.0
    if acc_e > 0 and pe:
        po[-1] += acc_o
        pe[-1] += acc_e
    po, pe = np.array(po), np.array(pe)
    stat = np.sum((po - pe) ** 2 / pe)
    return stats.chi2.sf(stat, len(pe) - 1)


def hemisphere_bins(pdf_fn, wo, n_cos=16, n_phi=32, sub=6):
    """Expected probability of each (cos θ, φ) bin of the upper hemisphere under the solid-angle
    density pdf_fn(wo, wi): midpoint rule on sub × sub points per bin (dω = dcosθ dφ)."""
    c_edges = np.linspace(0.0, 1.0, n_cos + 1)
    p_edges = np.linspace(-np.pi, np.pi, n_phi + 1)
    dc, dp = 1.0 / n_cos / sub, 2 * np.pi / n_phi / sub
    cc = (np.arange(n_cos * sub) + 0.5) * dc
    pp = -np.pi + (np.arange(n_phi * sub) + 0.5) * dp
    C, P = np.meshgrid(cc, pp, indexing="ij")
    s = np.sqrt(np.maximum(0.0, 1 - C**2))
    wi = np.stack([s * np.cos(P), s * np.sin(P), C], axis=-1).reshape(-1, 3)
    v = pdf_fn(wo, wi).reshape(n_cos * sub, n_phi * sub) * dc * dp
    return v.reshape(n_cos, sub, n_phi, sub).sum(axis=(1, 3)), c_edges, p_edges


def hemisphere_counts(wi, n_cos=16, n_phi=32):
    up = wi[:, 2] > 0
    h, _, _ = np.histogram2d(
        wi[up, 2], np.arctan2(wi[up, 1], wi[up, 0]), bins=[n_cos, n_phi], range=[[0, 1], [-np.pi, np.pi]]
    )
    return h
