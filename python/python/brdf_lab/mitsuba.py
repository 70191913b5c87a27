"""Mitsuba 3 BSDF plugin: any brdf-lab BRDF with any brdf-lab direction sampler.

    import mitsuba as mi
    mi.set_variant("llvm_ad_rgb")            # or "scalar_rgb", "llvm_ad_mono", ...
    import brdf_lab.mitsuba                   # registers the BSDF type "brdf_lab"
    bsdf = mi.load_dict({"type": "brdf_lab", "brdf": "ggx:alpha=0.2", "sampler": "adaptive"})

Parameters (strings, as in a scene file): ``brdf`` — a brdf-lab spec (``"ggx:alpha=0.2"``,
``"rgl:PATH.bsdf"``, …); ``sampler`` — a direction sampler of the registry (default
``"adaptive"``); ``seed`` — integer (default 1); ``options`` — sampler options as
``"key=value,key=value"`` (e.g. ``"slices=30,mixture=true"``).

Conventions: Mitsuba's local frame has z = normal like brdf-lab's; Mitsuba's ``si.wi`` (towards
the viewer) is brdf-lab's ``wo`` and Mitsuba's sampled ``bs.wo`` (towards the light) is
brdf-lab's ``wi``. ``sample`` returns the weight ``f·cos θ / pdf`` and the pdf per unit solid
angle; ``eval`` returns ``f·cos θ``. Vectorised variants make one brdf-lab call per Mitsuba
call (all lanes at once, through NumPy), never one per lane. Rendering with a Python BSDF in
an ``llvm_*`` variant needs evaluated (non-symbolic) loops and calls:
``dr.set_flag(dr.JitFlag.SymbolicLoops, False)``, ``dr.set_flag(dr.JitFlag.SymbolicCalls,
False)`` (:func:`evaluated_mode` does both).

Mitsuba is an optional dependency (``pip install "./python[mitsuba]"``); the core
``brdf_lab`` package never imports it. Built samplers are cached per
``(brdf, sampler, seed, options)``, since Mitsuba instantiates plugins often (its χ² adapter
does so per call).
"""

from __future__ import annotations

import json
from typing import Dict, Tuple

import numpy as np

import brdf_lab

try:
    import drjit as dr
    import mitsuba as mi
except ImportError as e:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        "brdf_lab.mitsuba needs Mitsuba 3: pip install \"./python[mitsuba]\" (mitsuba, drjit)"
    ) from e

__all__ = ["BrdfLabBSDF", "register", "evaluated_mode", "parse_options"]

_CACHE: Dict[Tuple, "brdf_lab.DirectionSampler"] = {}


def parse_options(text: str) -> dict:
    """``"slices=30,mixture=true,anisotropic_slices=[16,8]"`` → ``{"slices": 30, "mixture": True,
    "anisotropic_slices": [16, 8]}`` (commas inside brackets do not split)."""
    out = {}
    items, depth, cur = [], 0, ""
    for ch in text or "":
        depth += (ch == "[") - (ch == "]")
        if ch == "," and depth == 0:
            items.append(cur)
            cur = ""
        else:
            cur += ch
    items.append(cur)
    for item in filter(None, (s.strip() for s in items)):
        if "=" not in item:
            raise ValueError(f"sampler option {item!r} is not key=value")
        k, v = (s.strip() for s in item.split("=", 1))
        low = v.lower()
        if v.startswith("["):
            out[k] = json.loads(v)
        elif low in ("true", "false"):
            out[k] = low == "true"
        else:
            try:
                out[k] = int(v)
            except ValueError:
                try:
                    out[k] = float(v)
                except ValueError:
                    out[k] = v
    return out


def _sampler(spec: str, name: str, seed: int, options: str) -> "brdf_lab.DirectionSampler":
    key = (spec, name, seed, options)
    s = _CACHE.get(key)
    if s is None:
        s = brdf_lab.DirectionSampler(name, spec, seed=seed, **parse_options(options))
        _CACHE[key] = s
    return s


def evaluated_mode() -> None:
    """Switch Dr.Jit to evaluated loops and calls (needed to render with this plugin in a JIT
    variant: its methods convert their arguments to NumPy)."""
    dr.set_flag(dr.JitFlag.SymbolicLoops, False)
    dr.set_flag(dr.JitFlag.SymbolicCalls, False)


def _scalar() -> bool:
    return mi.variant().startswith("scalar")


def _float_dtype():
    return np.float64 if "double" in mi.variant() else np.float32


def _np3(v, n=None) -> np.ndarray:
    """A Mitsuba 3-vector (scalar or (3, N) JIT array) as an (N, 3) float64 array."""
    a = np.array(v, dtype=np.float64)
    a = a.reshape(3, -1).T if a.ndim == 2 else a.reshape(1, 3)
    if n is not None and a.shape[0] != n:
        a = np.broadcast_to(a, (n, 3))
    return a


def _np1(v, n=None, dtype=np.float64) -> np.ndarray:
    a = np.atleast_1d(np.array(v, dtype=dtype))
    if n is not None and a.shape[0] != n:
        a = np.broadcast_to(a, (n,))
    return a


def _width(*xs) -> int:
    return max(int(dr.width(x)) for x in xs)


def _vec3(a: np.ndarray):
    if _scalar():
        return mi.Vector3f(*(float(x) for x in a[0]))
    return mi.Vector3f(np.ascontiguousarray(a.T, dtype=_float_dtype()))


def _float(a: np.ndarray):
    if _scalar():
        return mi.Float(float(a[0]))
    return mi.Float(np.ascontiguousarray(a, dtype=_float_dtype()))


def _color(rgb: np.ndarray):
    """(N, 3) linear RGB as the variant's spectrum (luminance in mono variants)."""
    if mi.is_rgb:
        if _scalar():
            return mi.Color3f(*(float(x) for x in rgb[0]))
        return mi.Color3f(np.ascontiguousarray(rgb.T, dtype=_float_dtype()))
    y = rgb @ np.array([0.2126, 0.7152, 0.0722])
    if _scalar():
        return mi.Color1f(float(y[0]))
    return mi.Color1f(np.ascontiguousarray(y[None, :], dtype=_float_dtype()))


def _clean(wo: np.ndarray, active: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Directions safe to hand to brdf-lab (inactive / degenerate lanes → +z) and the mask of
    lanes whose results count."""
    ok = active & np.all(np.isfinite(wo), axis=1) & (np.linalg.norm(wo, axis=1) > 0)
    return np.where(ok[:, None], wo, np.array([0.0, 0.0, 1.0])), ok


class _Base:
    """Placeholder replaced by :func:`register` (the BSDF base class depends on the variant)."""


BrdfLabBSDF = _Base


def register() -> type:
    """Define the plugin class for the current Mitsuba variant and register it as ``"brdf_lab"``
    (done on import when a variant is set; call again after ``mi.set_variant``)."""
    global BrdfLabBSDF
    if mi.variant() is None:
        raise RuntimeError("set a Mitsuba variant (mi.set_variant) before registering brdf_lab")
    if mi.is_polarized or mi.is_spectral:
        raise RuntimeError(f"brdf_lab supports the rgb and mono variants, not {mi.variant()}")

    class BrdfLabBSDF(mi.BSDF):  # noqa: N801 - Mitsuba naming
        """A brdf-lab BRDF sampled by a brdf-lab direction sampler (see the module docs)."""

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.spec = str(props["brdf"]) if "brdf" in props else "ggx:alpha=0.2"
            self.sampler_name = str(props["sampler"]) if "sampler" in props else "adaptive"
            self.seed = int(props["seed"]) if "seed" in props else 1
            self.options = str(props["options"]) if "options" in props else ""
            self.sampler = _sampler(self.spec, self.sampler_name, self.seed, self.options)
            self.brdf = self.sampler.brdf
            flags = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.FrontSide
            self.m_components = [flags]
            self.m_flags = flags

        def _enabled(self, ctx) -> bool:
            return bool(ctx.is_enabled(mi.BSDFFlags.GlossyReflection, 0))

        def sample(self, ctx, si, sample1, sample2, active=True):
            n = _width(si.wi, sample2)
            wo, ok = _clean(_np3(si.wi, n), _np1(active, n, bool))
            u = np.clip(np.array(sample2, dtype=np.float64).reshape(2, -1).T, 0.0, 1.0)
            u = np.broadcast_to(u, (n, 2))
            ok &= self._enabled(ctx)
            wi, pdf, f = self.sampler.sample(wo, u, rgb=True)
            good = ok & (pdf > 0) & (wi[:, 2] > 0) & (wo[:, 2] > 0)
            weight = np.where(good[:, None], f * (wi[:, 2] / np.where(good, pdf, 1.0))[:, None], 0.0)
            pdf = np.where(good, pdf, 0.0)
            if _scalar():
                bs = mi.BSDFSample3f()
            else:
                bs = dr.zeros(mi.BSDFSample3f, n)
            bs.wo = _vec3(wi)
            bs.pdf = _float(pdf)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = mi.UInt32(0)
            return bs, _color(weight)

        def eval(self, ctx, si, wo, active=True):
            n = _width(si.wi, wo)
            v, ok = _clean(_np3(si.wi, n), _np1(active, n, bool))
            w, ok2 = _clean(_np3(wo, n), ok)
            f = self.brdf.eval_rgb(v, w) * np.maximum(w[:, 2], 0.0)[:, None]
            f[~(ok2 & self._enabled(ctx))] = 0.0
            return _color(f)

        def pdf(self, ctx, si, wo, active=True):
            n = _width(si.wi, wo)
            v, ok = _clean(_np3(si.wi, n), _np1(active, n, bool))
            w, ok2 = _clean(_np3(wo, n), ok)
            p = self.sampler.pdf(v, w)
            # a reflection BSDF: no density below the horizon (samples there have weight 0)
            p[~(ok2 & self._enabled(ctx)) | (w[:, 2] <= 0) | (v[:, 2] <= 0)] = 0.0
            return _float(p)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def traverse(self, callback):
            pass

        def to_string(self):
            return f"BrdfLabBSDF[brdf={self.spec!r}, sampler={self.sampler_name!r}]"

    mi.register_bsdf("brdf_lab", lambda props: BrdfLabBSDF(props))
    globals()["BrdfLabBSDF"] = BrdfLabBSDF
    return BrdfLabBSDF


if mi.variant() is not None:
    register()
