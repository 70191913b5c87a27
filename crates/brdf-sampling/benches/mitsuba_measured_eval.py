#!/usr/bin/env python3
"""Mitsuba 3's `measured` BSDF (RGL .bsdf files): throughput of `bsdf.sample` beside `bsdf.eval`
at arbitrary directions, at one fixed outgoing direction (the roofline of issue 29's RGL goal:
can an exact sampler that evaluates f at >= 1 point it did not construct reach Mitsuba's sample
rate at all?).

A copy of the peers' `mitsuba_measured.py` timing (llvm_ad_rgb variant, one wavefront of N lanes,
inputs evaluated before the clock starts, median of R repeats, the first repeat includes the JIT
compilation of the kernel) with an `eval` mode added:
  - sample: bsdf.sample(ctx, si, u1, u2) with the uniforms precomputed (as the peer script);
  - eval:   bsdf.eval(ctx, si, wi) at N directions wi drawn uniformly on the upper hemisphere
            (precomputed), i.e. f·cos at points the BSDF's own warp did not produce;
  - eval_pdf: bsdf.eval_pdf(ctx, si, wi) at the same directions (value and density together,
            what a MIS renderer asks at a light sample).
Prints one JSON line per (theta_o, mode) with M evaluations (or samples) per second.
Usage: mitsuba_measured_eval.py FILE.bsdf [-n N] [--theta-o 0 30 60 80] [--repeat 5]
       [--modes sample eval eval_pdf]
"""
import argparse, json, time
import numpy as np
import mitsuba as mi
import drjit as dr

ap = argparse.ArgumentParser()
ap.add_argument("file"); ap.add_argument("-n", type=int, default=1_000_000)
ap.add_argument("--theta-o", type=float, nargs="+", default=[0, 30, 60, 80])
ap.add_argument("--repeat", type=int, default=5)
ap.add_argument("--modes", nargs="+", default=["sample", "eval", "eval_pdf"])
a = ap.parse_args()
mi.set_variant("llvm_ad_rgb")
bsdf = mi.load_dict({"type": "measured", "filename": a.file})


def frame_si(n, wo):
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = wo                       # Mitsuba's wi is the direction towards the viewer (our ωo)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    return si


def timed(run, outputs):
    times = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        out = run()
        dr.eval(*outputs(out)); dr.sync_thread()
        times.append(time.perf_counter() - t0)
    return times


for th in a.theta_o:
    t = np.radians(th)
    n = a.n
    wo = mi.Vector3f(float(np.sin(t)), 0.0, float(np.cos(t)))
    si = frame_si(n, wo)
    ctx = mi.BSDFContext()
    sampler = mi.load_dict({"type": "independent"})
    sampler.seed(7, n)
    u1 = sampler.next_1d(); u2 = sampler.next_2d()
    # Uniform directions on the upper hemisphere (z uniform in (0, 1]).
    rng = np.random.default_rng(11)
    z = 1.0 - rng.random(n); phi = 2 * np.pi * rng.random(n); r = np.sqrt(np.maximum(0.0, 1 - z * z))
    wi = mi.Vector3f(mi.Float(r * np.cos(phi)), mi.Float(r * np.sin(phi)), mi.Float(z))
    dr.eval(u1, u2, wi); dr.sync_thread()
    for mode in a.modes:
        if mode == "sample":
            times = timed(lambda: bsdf.sample(ctx, si, u1, u2), lambda o: (o[0].wo, o[0].pdf, o[1]))
        elif mode == "eval":
            times = timed(lambda: bsdf.eval(ctx, si, wi), lambda o: (o,))
        elif mode == "eval_pdf":
            times = timed(lambda: bsdf.eval_pdf(ctx, si, wi), lambda o: (o[0], o[1]))
        else:
            raise SystemExit(f"unknown mode {mode}")
        rec = {"theta_o": th, "mode": mode, "n": n, "mps": n / np.median(times) / 1e6,
               "mps_best": n / min(times) / 1e6, "ms_runs": [round(1e3 * x, 2) for x in times]}
        print(json.dumps(rec), flush=True)
