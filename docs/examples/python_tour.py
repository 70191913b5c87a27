"""brdf-lab from Python, notebook style: sample a BRDF, plot, validate (CI runs this file).

    pip install ./python            # from the repository root
    python docs/examples/python_tour.py --out tour-out

Each `# %%` cell runs on its own in Jupyter / VS Code; matplotlib is used when installed.
"""

# %% Setup
import argparse
import pathlib

import numpy as np

import brdf_lab

parser = argparse.ArgumentParser()
parser.add_argument("--out", default="tour-out")
args, _ = parser.parse_known_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)

# %% A BRDF and the models it could have been
ggx = brdf_lab.Brdf("ggx:alpha=0.2")
print(len(brdf_lab.models()), "models, e.g.", [p["key"] for p in brdf_lab.models()[0]["params"]])
theta = np.radians(45.0)
wo = np.array([np.sin(theta), 0.0, np.cos(theta)])

# %% Sample it with the adaptive quadtree sampler and check the estimator
sampler = brdf_lab.DirectionSampler("adaptive", ggx, seed=1)
print(sampler.build_report.splitlines()[0], f"({sampler.bytes_used / 1024:.0f} KiB)")
u = np.random.default_rng(1).random((200_000, 2))
wi, pdf, f = sampler.sample(wo, u)
ok = pdf > 0
albedo = np.mean(np.where(ok, f * wi[:, 2] / np.where(ok, pdf, 1), 0.0))
print(f"directional albedo at 45°: {albedo:.4f} (f·cos/pdf averaged over {len(u)} samples)")
assert np.allclose(sampler.pdf(wo, wi[ok]), pdf[ok], rtol=1e-9)

# %% Plot the samples on the projected disc (x, y of wi)
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4, 4))
    ax.hist2d(wi[:, 0], wi[:, 1], bins=128, range=[[-1, 1], [-1, 1]], cmap="magma")
    ax.set_aspect("equal")
    ax.set_title("ggx α=0.2, θo=45°: adaptive samples")
    fig.savefig(out / "samples.png", dpi=100)
    print("wrote", out / "samples.png")
except ImportError:
    h, _, _ = np.histogram2d(wi[:, 0], wi[:, 1], bins=16, range=[[-1, 1], [-1, 1]])
    print("(matplotlib not installed) sample counts on the projected disc, 16 × 16:")
    for row in (h.T[::-1] / h.max() * 9).astype(int):
        print("".join(" .:-=+*#%@"[v] for v in row))

# %% An environment map from an array, and the generic partition sampler
sky = np.ones((64, 128, 3))
sky[10:14, 90:96] = 500.0
env = brdf_lab.EnvMapSampler("envmap-adaptive", sky, seed=2)
uv, pdf_uv, dirs, pdf_sa = env.sample(10_000)
patch = (uv[:, 1] >= 10 / 64) & (uv[:, 1] < 14 / 64) & (uv[:, 0] >= 90 / 128) & (uv[:, 0] < 96 / 128)
print(f"envmap: {patch.mean():.2f} of the samples in the bright patch (it holds {24 * 500 / (24 * 500 + 64 * 128 - 24):.2f} of the radiance, before sin θ)")
table = np.outer(np.hanning(32) + 0.01, np.hanning(48) + 0.01)
part = brdf_lab.PartitionSampler(table, method="adaptive")
print("partition sampler:", {k: part.build_report[k] for k in ("leaves", "depth", "bytes_used")})

# %% Validate: the library's χ² / KS / consistency suite, with the CLI's files
result = brdf_lab.validate("adaptive", "ggx:alpha=0.2", theta_o=[45.0], samples=20_000, json=out / "validate.json")
print(f"validate: {len(result.tests)} tests, passed = {result.passed}")
assert result.passed
