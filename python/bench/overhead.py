"""The Python package's overhead over the Rust call it wraps, at 1,000 scan and 2,000 model
points: the median wall time of `pficp.register` against the median of the same
`Request::check` + `Request::run` in Rust (host/examples/register_timing.rs) on the same
clouds, N runs each, alternated in rounds so that the machine's load falls on both. Two
workloads: PF-ICP's defaults (about 0.2 s, whose run-to-run spread hides a millisecond)
and one ICP iteration (under a millisecond of Rust: the overhead stands out; what the
binding adds, the arrays in and the result out, does not depend on the method).

    python python/bench/overhead.py [N]      (from the workspace root, the package installed)
"""

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import pficp

ROOT = Path(__file__).resolve().parents[2]


def clouds(seed=3):
    """A bumpy ellipsoid (2,000 points) and 1,000 points of one side of it, turned and moved."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(2000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    model = d * (1 + 0.15 * np.sin(3 * d[:, 0]) * np.cos(2 * d[:, 1]))[:, None] * [60.0, 35.0, 25.0]
    side = model[model[:, 2] > -5][:1000]
    a = np.radians(30)
    r = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    return model, np.ascontiguousarray((side - [4.0, -2.0, 1.0]) @ r + rng.normal(scale=0.1, size=side.shape))


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    model, scan = clouds()
    with tempfile.TemporaryDirectory() as tmp:
        m, s = Path(tmp) / "model.ply", Path(tmp) / "scan.ply"
        pficp.write_cloud(m, model)
        pficp.write_cloud(s, scan)
        cargo = ["cargo", "run", "-q", "--release", "-p", "pficp-host", "--example", "register_timing", "--"]
        subprocess.run(cargo + [m, s, "1"], cwd=ROOT, check=True, capture_output=True)
        print(f"{len(scan)} scan + {len(model)} model points, medians of 5 rounds of {n} runs")
        for method, iterations in [("pf-icp", 50), ("icp", 1)]:
            rust, python = [], []
            for _ in range(5):
                args = [m, s, str(n), method, str(iterations)]
                out = subprocess.run(cargo + args, cwd=ROOT, check=True, capture_output=True, text=True)
                rust.append(float(out.stdout))
                times = []
                for _ in range(n):
                    t = time.perf_counter()
                    pficp.register(model, scan, method=method, iterations=iterations)
                    times.append((time.perf_counter() - t) * 1e3)
                python.append(statistics.median(times))
            r, p = statistics.median(rust), statistics.median(python)
            rounds = lambda v: ", ".join(f"{x:.3f}" for x in v)  # noqa: E731
            print(f"{method}, {iterations} iterations:")
            print(f"  rust   Request::check + run  {r:9.3f} ms  (rounds: {rounds(rust)})")
            print(f"  python pficp.register        {p:9.3f} ms  (rounds: {rounds(python)})")
            print(f"  overhead                     {p - r:9.3f} ms")

if __name__ == "__main__":
    main()
