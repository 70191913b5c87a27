"""Python `DirectionSampler.sample` against the Rust batch path (examples/batch_bench.rs) for
10⁶ queries at θo = 45°, same machine, same run, same thread count (docs/benchmarks.md).

    python python/examples/bench_sample.py [--rust target/release/examples/batch_bench]
"""

import argparse
import statistics
import subprocess
import time

import numpy as np

import brdf_lab

p = argparse.ArgumentParser()
p.add_argument("--rust", default="target/release/examples/batch_bench")
p.add_argument("-n", type=int, default=1_000_000)
p.add_argument("--repeats", type=int, default=5)
a = p.parse_args()

wo = np.array([np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4)])
for name, spec in [("adaptive", "ggx:alpha=0.2"), ("cosine", "lambert")]:
    rust = subprocess.run([a.rust, name, spec, str(a.n), str(a.repeats)], capture_output=True, text=True, check=True)
    rust_ns = float(rust.stdout.split("median ")[1].split(" ns")[0])
    s = brdf_lab.DirectionSampler(name, spec, seed=1)
    u = np.random.default_rng(1).random((a.n, 2))
    rows = {}
    for label, arg in [("u given (N, 2)", u), ("u = N (generator)", a.n)]:
        ts = []
        for r in range(a.repeats):
            t0 = time.perf_counter()
            s.sample(wo, arg, seed=r)
            ts.append(time.perf_counter() - t0)
        rows[label] = statistics.median(ts) * 1e9 / a.n
    print(f"{name:9} {spec:15} threads={brdf_lab.num_threads()} rust {rust_ns:7.1f} ns/sample | "
          + " | ".join(f"python {k}: {v:7.1f} ns ({v / rust_ns:.2f}×)" for k, v in rows.items()))
