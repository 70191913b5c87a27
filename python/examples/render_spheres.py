#!/usr/bin/env python3
"""Spheres under an HDR environment map, rendered by Mitsuba 3 through the ``brdf_lab`` plugin and
through Mitsuba's native plugins for the same material, compared statistically (issue 30).

Materials (one sphere per image, radius 1, seen from distance 4 with a 35° field of view):

* ``ggx``: brdf-lab's ``ggx:alpha=A`` (Schlick ``f0`` = 1 by default, i.e. F ≡ 1) against
  Mitsuba's ``roughconductor`` with ``distribution="ggx"``, ``alpha=A``, ``material="none"``
  (Mitsuba's perfectly reflecting conductor: F ≡ 1) and ``sample_visible=true``. Both use the
  separable Smith G of GGX, so the BRDFs are identical.
* ``rgl:FILE``: an RGL ``.bsdf`` file through brdf-lab's ``rgl:FILE`` against Mitsuba's
  ``measured`` plugin on the same file.

Colour: both sides return RGB (``Brdf.eval_rgb`` in the plugin; ``measured`` reads the file's
``rgb`` table in the ``*_rgb`` variants; GGX is grey), so images are compared per RGB channel.
Lighting: both renders use Mitsuba's own ``envmap`` emitter with the same map and transform, so
brdf-lab's map-orientation convention plays no role here. Integrator: Mitsuba's ``direct`` (a
convex sphere has no interreflection, so this is the whole light transport) with either MIS of
one emitter and one BSDF sample per pass (``--strategy mis``) or BSDF sampling alone
(``--strategy bsdf``, which exercises only the samplers' ``sample``).

Modes:

* ``compare``: K independent renders (distinct seeds) of each configuration; per-block means
  (``--block`` × ``--block`` pixels inside the sphere) of every render; Welch's t per block and
  channel between the native render and each plugin render, plus one Welch t of the mean over
  the sphere (a uniform scale); family-wise α (``--alpha``): α/2 for the mean, α/2 shared by the
  blocks × channels with Šidák's correction. ``--scale S`` multiplies the plugin's BRDF by S
  (a deliberately wrong material: the test must then reject). ``--clamp-native`` clamps the
  native BSDF's values at 0, as brdf-lab's RGL reader does with the files' negative entries
  (Mitsuba's ``measured`` keeps them).
* ``timing``: a high-spp native reference, then for each configuration R renders at each spp of
  ``--spp-list``: wall time (median, after a warm-up render) and RMSE over the sphere's pixels
  against the reference; the equal-time RMSE follows from RMSE² ∝ 1/time.

Writes ``results.json`` (and, with ``--png``, a small tonemapped montage) to ``--out``. Needs
``pip install "./python[mitsuba]"``; ``llvm_*`` variants need libllvm19. Variants: ``llvm_ad_rgb``
(default) or ``scalar_rgb`` (correct but slow: Mitsuba then calls the Python plugin once per
lane); ``measured`` refuses the RGL ``*_rgb`` files in mono and spectral variants, and the
plugin has no spectral variant.

Example::

    python python/examples/render_spheres.py compare --map ../shared/data/envmaps/grace_probe_latlong.hdr \
        --materials ggx rgl:../shared/data/measured/rgl/paper_white_rgb.bsdf --spp 64 --repeats 8 --out out/
"""

from __future__ import annotations

import argparse
import json
import math
import os
import struct
import sys
import time
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("BRDF_LAB_SHARED", REPO / ".." / "shared"))
DEFAULT_MAP = SHARED / "data" / "envmaps" / "grace_probe_latlong.hdr"

# Camera and sphere (see the module docs).
DISTANCE, RADIUS, FOV = 4.0, 1.0, 35.0
# brdf-lab's samplers for GGX: the tabulated exact sampler and the analytic (visible-normal) one.
GGX_SAMPLERS = ("adaptive-exact", "analytic")
RGL_SAMPLERS = ("adaptive-exact",)
SAMPLER_OPTIONS = "slices=30"


class RenderError(Exception):
    """A user-facing error (bad argument, missing file or dependency): one line, exit status 2."""


@dataclass(frozen=True)
class Material:
    """One material, as a native Mitsuba BSDF and as a brdf-lab spec."""

    label: str
    native: dict
    spec: str
    samplers: Sequence[str]


def parse_material(text: str, alpha: float) -> Material:
    """``ggx`` (with ``alpha``) or ``rgl:PATH`` → a :class:`Material` (clear error otherwise)."""
    if text == "ggx":
        if not (0.001 <= alpha <= 2.0):
            raise RenderError(f"--alpha {alpha} is outside brdf-lab's GGX range [0.001, 2]")
        native = {
            "type": "roughconductor", "distribution": "ggx", "alpha": alpha,
            "material": "none", "sample_visible": True,
        }
        return Material(f"ggx-a{alpha:g}", native, f"ggx:alpha={alpha!r}", GGX_SAMPLERS)
    if text.startswith("rgl:"):
        path = Path(text[4:]).expanduser()
        if not path.is_file():
            raise RenderError(f"RGL file {path} not found")
        return Material(path.stem, {"type": "measured", "filename": str(path.resolve())},
                        f"rgl:{path.resolve()}", RGL_SAMPLERS)
    raise RenderError(f"unknown material {text!r}: expected 'ggx' or 'rgl:PATH.bsdf'")


def setup_mitsuba(variant: str):
    """Import Mitsuba, set ``variant`` and register the plugin (evaluated mode in JIT variants)."""
    try:
        import drjit as dr
        import mitsuba as mi
    except ImportError as e:
        raise RenderError(f"Mitsuba 3 is not installed ({e}): pip install \"./python[mitsuba]\"") from e
    if variant not in mi.variants():
        raise RenderError(f"Mitsuba variant {variant!r} is not available; have {', '.join(mi.variants())}")
    try:
        mi.set_variant(variant)
        if not variant.startswith("scalar"):
            dr.eval(mi.Float([1.0, 2.0]))
    except Exception as e:  # noqa: BLE001 - Dr.Jit raises various errors without LLVM
        raise RenderError(f"cannot use {variant} ({e}); for llvm_* install libllvm19") from e
    try:
        import brdf_lab.mitsuba as plugin  # registers "brdf_lab" for the variant on import

        plugin.register()
    except RuntimeError as e:
        raise RenderError(str(e)) from e
    if not variant.startswith("scalar"):
        plugin.evaluated_mode()
    _register_scaled(mi)
    return mi, dr


def _register_scaled(mi) -> None:
    """A diagnostic BSDF ``scaled_bsdf``: a nested BSDF times a constant (eval and sample weight;
    the pdf is unchanged), optionally with negative values clamped to 0 (``clamp``). Used to
    show that the comparison rejects a wrong material, and to apply brdf-lab's clamping of
    negative RGL entries to Mitsuba's ``measured`` (``--clamp-native``)."""
    import drjit as dr

    class ScaledBSDF(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.nested = props["nested"]
            self.scale = float(props["scale"])
            self.clamp = bool(props["clamp"]) if "clamp" in props else False
            self.m_components = [self.nested.flags()]
            self.m_flags = self.nested.flags()

        def sample(self, ctx, si, sample1, sample2, active=True):
            bs, w = self.nested.sample(ctx, si, sample1, sample2, active)
            return bs, self._out(w)

        def eval(self, ctx, si, wo, active=True):
            return self._out(self.nested.eval(ctx, si, wo, active))

        def _out(self, v):
            return (dr.maximum(v, 0.0) if self.clamp else v) * self.scale

        def pdf(self, ctx, si, wo, active=True):
            return self.nested.pdf(ctx, si, wo, active)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

    mi.register_bsdf("scaled_bsdf", lambda props: ScaledBSDF(props))


def plugin_bsdf(material: Material, sampler: str, scale: float = 1.0) -> dict:
    """The brdf_lab plugin's BSDF dict for ``material`` and ``sampler`` (× ``scale``)."""
    d = {"type": "brdf_lab", "brdf": material.spec, "sampler": sampler, "options": SAMPLER_OPTIONS}
    return d if scale == 1.0 else {"type": "scaled_bsdf", "scale": scale, "nested": d}


def scene_dict(mi, bsdf: dict, map_path: Path, res: int, spp: int, strategy: str) -> dict:
    """One sphere with ``bsdf`` under ``map_path``'s ``envmap``, ``res`` × ``res`` pixels."""
    if strategy == "mis":
        integ = {"type": "direct", "emitter_samples": 1, "bsdf_samples": 1}
    elif strategy == "bsdf":
        integ = {"type": "direct", "emitter_samples": 0, "bsdf_samples": 1}
    else:
        raise RenderError(f"unknown strategy {strategy!r}: expected mis or bsdf")
    return {
        "type": "scene",
        "integrator": integ,
        "sensor": {
            "type": "perspective", "fov": FOV, "fov_axis": "x",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, DISTANCE], target=[0, 0, 0],
                                                       up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "emitter": {"type": "envmap", "filename": str(map_path)},
        "ball": {"type": "sphere", "radius": RADIUS, "bsdf": bsdf},
    }


def load_scene(mi, scene: dict):
    """``mi.load_dict`` with Mitsuba's errors (unreadable map or RGL file, a plugin the variant
    lacks) as a one-line :class:`RenderError`."""
    try:
        return mi.load_dict(scene)
    except Exception as e:  # noqa: BLE001 - Mitsuba raises RuntimeError and others
        lines = [ln for ln in str(e).splitlines() if ln.strip()]
        raise RenderError(f"Mitsuba cannot load the scene: {lines[-1] if lines else type(e).__name__}") from e


def sphere_mask(res: int) -> np.ndarray:
    """Pixels whose whole footprint sees the sphere (all four corners' rays hit it; the sphere's
    image is a disc, so that suffices), with a 2 % margin of the pixel size."""
    t = math.tan(math.radians(FOV) / 2)
    edges = (np.arange(res + 1) - res / 2) * (2 * t / res)  # image-plane coordinates at z = 1
    y, x = np.meshgrid(edges, edges, indexing="ij")
    # a ray (x, y, 1) from the eye hits the sphere iff sin²(angle to the axis) ≤ (r/D)²
    hit = (x * x + y * y) / (1 + x * x + y * y) <= (RADIUS / DISTANCE) ** 2 * (1 - 0.02 * 2 * t / res)
    return hit[:-1, :-1] & hit[1:, :-1] & hit[:-1, 1:] & hit[1:, 1:]


def block_means(img: np.ndarray, mask: np.ndarray, b: int) -> np.ndarray:
    """(n_blocks, 3) means of the b × b blocks entirely inside ``mask``."""
    h, w = mask.shape
    out = []
    for i in range(0, h - b + 1, b):
        for j in range(0, w - b + 1, b):
            if mask[i:i + b, j:j + b].all():
                out.append(img[i:i + b, j:j + b].reshape(-1, img.shape[2]).mean(axis=0))
    if not out:
        raise RenderError(f"no {b}×{b} block lies inside the sphere: raise --res or lower --block")
    return np.array(out)


def render_once(mi, scene, spp: int, seed: int) -> np.ndarray:
    """One render as an (H, W, 3) float64 array."""
    return np.array(mi.render(scene, seed=seed, spp=spp), dtype=np.float64)[..., :3]


def render_passes(mi, dr, scene, spp: int, seed: int, max_spp_per_pass: int) -> np.ndarray:
    """``spp`` samples per pixel in passes of at most ``max_spp_per_pass`` (memory), averaged."""
    acc, done, k = None, 0, 0
    while done < spp:
        s = min(max_spp_per_pass, spp - done)
        img = render_once(mi, scene, s, seed * 100_003 + k) * s
        acc = img if acc is None else acc + img
        done += s
        k += 1
    return acc / spp


def welch(a: np.ndarray, b: np.ndarray):
    """Welch's t and its Satterthwaite degrees of freedom along axis 0 (replicates)."""
    ka, kb = a.shape[0], b.shape[0]
    va, vb = a.var(axis=0, ddof=1) / ka, b.var(axis=0, ddof=1) / kb
    se2 = va + vb
    t = (a.mean(axis=0) - b.mean(axis=0)) / np.sqrt(np.where(se2 > 0, se2, np.inf))
    df = se2 ** 2 / np.where(se2 > 0, va ** 2 / (ka - 1) + vb ** 2 / (kb - 1), 1.0)
    return t, np.maximum(df, 1.0)


def compare_replicates(native: np.ndarray, plugin: np.ndarray, mask: np.ndarray, block: int,
                       alpha: float) -> dict:
    """The agreement test between two stacks of K independent renders (K, H, W, 3): Welch's t per
    block and channel, and of the frame mean over the sphere; Šidák at family-wise ``alpha``."""
    from scipy import stats

    bn = np.array([block_means(im, mask, block) for im in native])  # (K, n_blocks, 3)
    bp = np.array([block_means(im, mask, block) for im in plugin])
    tb, dfb = welch(bn, bp)
    pb = 2 * stats.t.sf(np.abs(tb), dfb)
    fn = np.array([im[mask].mean() for im in native])
    fp = np.array([im[mask].mean() for im in plugin])
    tf, dff = welch(fn[:, None], fp[:, None])
    pf = float(2 * stats.t.sf(abs(tf[0]), dff[0]))
    # α/2 for the frame mean (a uniform scale: the most likely error, tested with all pixels),
    # α/2 shared by the blocks × channels with Šidák's correction (local differences)
    level_blocks = 1 - (1 - alpha / 2) ** (1 / pb.size)
    ratio = float(fp.mean() / fn.mean())
    ratio_se = float(ratio * math.sqrt(fp.var(ddof=1) / len(fp) / fp.mean() ** 2
                                       + fn.var(ddof=1) / len(fn) / fn.mean() ** 2))
    return {
        "blocks": int(bn.shape[1]), "block_tests": int(pb.size), "alpha": alpha,
        "level_frame": alpha / 2, "level_block": level_blocks,
        "p_min_block": float(pb.min()), "p_min_block_rgb": [float(x) for x in pb.min(axis=0)],
        "p_frame": pf, "max_abs_t_block": float(np.abs(tb).max()),
        "mean_ratio_plugin_over_native": ratio, "mean_ratio_se": ratio_se,
        "passed": bool(pf > alpha / 2 and pb.min() > level_blocks),
        "worst_block": _worst_block(bn, bp, tb, pb, mask, block),
    }


def write_png(disp: np.ndarray, path: Path) -> None:
    """An 8-bit RGB PNG of display values in [0, 1], written with the standard library (zlib)."""
    u8 = (np.clip(disp, 0, 1) * 255 + 0.5).astype(np.uint8)
    h, w = u8.shape[:2]
    raw = b"".join(b"\x00" + u8[i].tobytes() for i in range(h))

    def chunk(tag: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                     + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def _worst_block(bn, bp, tb, pb, mask: np.ndarray, block: int) -> dict:
    """Where the smallest block p-value is: block origin (row, column), channel, t, both means."""
    b, c = np.unravel_index(int(np.argmin(pb)), pb.shape)
    h, w = mask.shape
    origins = [(i, j) for i in range(0, h - block + 1, block) for j in range(0, w - block + 1, block)
               if mask[i:i + block, j:j + block].all()]
    return {"row": origins[b][0], "col": origins[b][1], "channel": "RGB"[c],
            "t_native_minus_plugin": float(tb[b, c]), "p": float(pb[b, c]),
            "native": float(bn[:, b, c].mean()), "plugin": float(bp[:, b, c].mean())}


def tonemap(img: np.ndarray) -> np.ndarray:
    """Linear RGB → display values in [0, 1] (Reinhard x/(1+x), then the sRGB curve)."""
    x = np.clip(img, 0.0, None)
    x = x / (1 + x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def t_map(native: np.ndarray, plugin: np.ndarray, mask: np.ndarray, cap: float = 4.0) -> np.ndarray:
    """Per-pixel Welch t of the luminance (plugin − native) as colours: red > 0, blue < 0, full
    at |t| = ``cap``; black outside the sphere."""
    lum = np.array([0.2126, 0.7152, 0.0722])
    t, _ = welch(plugin @ lum, native @ lum)
    a = np.clip(np.nan_to_num(t) / cap, -1, 1)
    rgb = np.stack([np.clip(a, 0, 1), np.zeros_like(a), np.clip(-a, 0, 1)], axis=-1)
    return np.where(mask[..., None], rgb, 0.0)


def write_montage(rows: List[List[np.ndarray]], path: Path, pad: int = 2) -> None:
    """Display-ready tiles (values in [0, 1]) in rows, padded with white, as one PNG."""
    h, w = rows[0][0].shape[:2]
    ncol = max(len(r) for r in rows)
    out = np.ones((len(rows) * (h + pad) - pad, ncol * (w + pad) - pad, 3))
    for i, r in enumerate(rows):
        for j, tile in enumerate(r):
            out[i * (h + pad):i * (h + pad) + h, j * (w + pad):j * (w + pad) + w] = tile
    write_png(out, path)


def run_compare(args, mi, dr, materials: List[Material]) -> dict:
    mask = sphere_mask(args.res)
    out: Dict[str, dict] = {}
    rows: List[List[np.ndarray]] = []
    for ci, m in enumerate(materials):
        nat = m.native
        if args.clamp_native:
            nat = {"type": "scaled_bsdf", "scale": 1.0, "clamp": True, "nested": nat}
        scene_n = load_scene(mi, scene_dict(mi, nat, args.map, args.res, args.spp, args.strategy))
        native = np.array([render_passes(mi, dr, scene_n, args.spp, args.seed + 1000 * ci + k, args.pass_spp)
                           for k in range(args.repeats)])
        row = [tonemap(native.mean(axis=0))]
        for si, s in enumerate(m.samplers):
            bsdf = plugin_bsdf(m, s, args.scale)
            scene_p = load_scene(mi, scene_dict(mi, bsdf, args.map, args.res, args.spp, args.strategy))
            base = args.seed + 1000 * ci + 100 * (si + 1)
            plugin = np.array([render_passes(mi, dr, scene_p, args.spp, base + k, args.pass_spp)
                               for k in range(args.repeats)])
            r = compare_replicates(native, plugin, mask, args.block, args.alpha)
            key = f"{m.label}/{s}"
            out[key] = r
            print(f"{key:40s} {'PASS' if r['passed'] else 'FAIL'}  plugin/native mean "
                  f"{r['mean_ratio_plugin_over_native']:.4f} ± {r['mean_ratio_se']:.4f}  "
                  f"p frame {r['p_frame']:.3g} (level {r['level_frame']:.3g}), min p of "
                  f"{r['block_tests']} blocks×channels {r['p_min_block']:.3g} "
                  f"(level {r['level_block']:.3g})",
                  flush=True)
            row += [tonemap(plugin.mean(axis=0)), t_map(native, plugin, mask)]
        rows.append(row)
    if args.png:
        # per material: native, then per plugin sampler its image and the per-pixel t map
        write_montage(rows, args.out / "compare.png")
    return out


def run_timing(args, mi, dr, materials: List[Material]) -> dict:
    mask = sphere_mask(args.res)
    out: Dict[str, dict] = {}
    rows: List[List[np.ndarray]] = []
    for ci, m in enumerate(materials):
        scene_ref = load_scene(mi, scene_dict(mi, m.native, args.map, args.res, args.ref_spp, args.strategy))
        t0 = time.perf_counter()
        ref = render_passes(mi, dr, scene_ref, args.ref_spp, 10_000 + ci, args.pass_spp)
        print(f"{m.label}: reference {args.ref_spp} spp (native) in {time.perf_counter() - t0:.1f} s",
              flush=True)
        row = [tonemap(ref)]
        confs = [("native", m.native)] + [(f"brdf_lab/{s}", plugin_bsdf(m, s)) for s in m.samplers]
        for name, bsdf in confs:
            scene = load_scene(mi, scene_dict(mi, bsdf, args.map, args.res, 1, args.strategy))
            for spp in args.spp_list:
                render_once(mi, scene, spp, 999)  # warm-up: kernels for this spp, sampler build
                times, errs = [], []
                for r in range(args.repeats):
                    t0 = time.perf_counter()
                    img = render_once(mi, scene, spp, 20_000 + 97 * r + spp)
                    times.append(time.perf_counter() - t0)
                    errs.append(float(np.sqrt(np.mean((img[mask] - ref[mask]) ** 2))))
                t, e = float(np.median(times)), float(np.median(errs))
                if spp == args.spp_list[-1]:
                    row.append(tonemap(img))
                out[f"{m.label}/{name}/{spp}"] = {"spp": spp, "seconds_median": t, "rmse_median": e,
                                                  "seconds": times, "rmse": errs}
                print(f"{m.label:24s} {name:26s} {spp:5d} spp  {t:8.3f} s  RMSE {e:.5g}", flush=True)
        # equal time: RMSE² ∝ 1/time, scaled to the native's time at each spp
        for spp in args.spp_list:
            tn = out[f"{m.label}/native/{spp}"]["seconds_median"]
            for name, _ in confs:
                c = out[f"{m.label}/{name}/{spp}"]
                c["rmse_at_native_time"] = c["rmse_median"] * math.sqrt(c["seconds_median"] / tn)
        rows.append(row)
    if args.png:
        # per material: the reference, then each configuration at the last spp of --spp-list
        write_montage(rows, args.out / "timing.png")
    return out


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["compare", "timing"])
    ap.add_argument("--map", type=Path, default=DEFAULT_MAP, help="HDR environment map (.hdr/.exr)")
    ap.add_argument("--materials", nargs="+", default=["ggx"], help="ggx and/or rgl:PATH.bsdf")
    ap.add_argument("--alpha-ggx", dest="ggx_alpha", type=float, default=0.2, help="GGX roughness α")
    ap.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (an rgb or mono one)")
    ap.add_argument("--strategy", choices=["mis", "bsdf"], default="mis")
    ap.add_argument("--res", type=int, default=64, help="image width = height (pixels)")
    ap.add_argument("--spp", type=int, default=64, help="compare: samples per pixel per render")
    ap.add_argument("--repeats", type=int, default=8, help="independent renders per configuration")
    ap.add_argument("--block", type=int, default=8, help="compare: block size (pixels)")
    ap.add_argument("--alpha", type=float, default=0.01, help="compare: family-wise significance level")
    ap.add_argument("--scale", type=float, default=1.0, help="compare: multiply the plugin's BRDF (a mutant)")
    ap.add_argument("--clamp-native", action="store_true",
                    help="compare: clamp the native BSDF's negative values to 0 (as brdf-lab's RGL reader)")
    ap.add_argument("--spp-list", type=int, nargs="+", default=[4, 16, 64], help="timing: spp values")
    ap.add_argument("--ref-spp", type=int, default=4096, help="timing: the native reference's spp")
    ap.add_argument("--pass-spp", type=int, default=256, help="at most this many spp per mi.render call")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--png", action="store_true", help="write small tonemapped PNGs to --out")
    ap.add_argument("--out", type=Path, default=Path("render-out"))
    args = ap.parse_args(argv)
    try:
        if not args.map.is_file():
            raise RenderError(f"environment map {args.map} not found (pass --map PATH)")
        for name in ("res", "spp", "repeats", "block", "ref_spp", "pass_spp"):
            if getattr(args, name) < 1:
                raise RenderError(f"--{name.replace('_', '-')} must be ≥ 1")
        if args.mode == "compare" and args.repeats < 2:
            raise RenderError("compare needs --repeats ≥ 2 (the test estimates variances from them)")
        if not (0 < args.alpha < 1) or not (0 < args.scale <= 10):
            raise RenderError("--alpha must be in (0, 1) and --scale in (0, 10]")
        if any(s < 1 for s in args.spp_list):
            raise RenderError("--spp-list values must be ≥ 1")
        materials = [parse_material(t, args.ggx_alpha) for t in args.materials]
        args.map = args.map.resolve()
        args.out.mkdir(parents=True, exist_ok=True)
        mi, dr = setup_mitsuba(args.variant)
        run = run_compare if args.mode == "compare" else run_timing
        res = run(args, mi, dr, materials)
    except RenderError as e:
        print(f"render_spheres: {e}", file=sys.stderr)
        return 2
    config = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}
    (args.out / "results.json").write_text(json.dumps({"config": config, "results": res}, indent=1))
    if args.mode == "compare" and not all(r["passed"] for r in res.values()):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
