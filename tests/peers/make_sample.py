#!/usr/bin/env python3
"""Write a small synthetic benchmark in the `pficp eval --export` format.

    python3 tests/peers/make_sample.py OUTDIR [--cases 6] [--known 2] [--seed 1]

For testing run_peers.py before (or besides) a real export. Shapes are
star-shaped bumpy surfaces x = r(u) u * (1.0, 0.7, 0.5) for unit directions u:

  synthetic  an asymmetric r(u); full scan                (symmetry: identity)
  partial    the same shape; scan = the half seen from a random direction
  symmetric  an r(u) invariant under 180 deg about z; full scan
             (symmetries: identity and Rz(180) about the origin)

These have "known_scale": null (the scale is unknown to the method). After
them come --known cases (default 2) whose scale the method is told,
alternately:

  metric       the partial family's shape and scan, scale exactly 1,
               "known_scale": 1.0
  known-scale  the synthetic family's shape and full scan, scale drawn as
               below, "known_scale" = that scale

Model: 2000 points; scan: 1000 points sampled independently of the model,
Gaussian noise sigma = 0.5 % of the model diagonal. Truth: random axis,
angle uniform in [0, 60] deg, scale uniform in [0.7, 1.3], translation
uniform in [-0.3, 0.3] diag per axis. The scan is written in scan
coordinates m = R^T (d - T) / s, so that d = s R m + T. The model is written
as binary_little_endian float and the scan as ascii double, to exercise both
PLY readers.
"""

import argparse
import json
import math
import os

import numpy as np

AXES = np.array([1.0, 0.7, 0.5])
MODEL_POINTS, SCAN_POINTS, NOISE_FRAC = 2000, 1000, 0.005
MAX_DEG, SCALE_RANGE, TRANS_FRAC = 60.0, (0.7, 1.3), 0.3


def radius_asym(u):
    x, y, z = u.T
    return 1 + 0.25 * np.sin(3 * x + 1) * np.cos(2 * y - 0.5) + 0.2 * np.cos(4 * z + 2 * x) \
        + 0.15 * np.sin(5 * y + 3 * z + 0.3)


def radius_sym(u):  # invariant under (x, y, z) -> (-x, -y, z)
    x, y, z = u.T
    return 1 + 0.3 * np.cos(4 * x * y + 2 * z) + 0.2 * np.sin(3 * x * x - 2 * z + 0.5)


def sample_surface(rng, n, radius, view=None):
    """n points of the surface; with `view`, only those whose direction faces it."""
    out = []
    while sum(len(o) for o in out) < n:
        u = rng.normal(size=(4 * n, 3))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        if view is not None:
            u = u[u @ view > 0.0]
        out.append(radius(u)[:, None] * u * AXES)
    return np.concatenate(out)[:n]


def rotation(axis, deg):
    axis = axis / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    a = math.radians(deg)
    return np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * k @ k


def write_ply(path, pts, binary):
    pts = np.asarray(pts)
    if binary:
        head = ("ply\nformat binary_little_endian 1.0\ncomment make_sample.py\n"
                f"element vertex {len(pts)}\nproperty float x\nproperty float y\nproperty float z\nend_header\n")
        with open(path, "wb") as f:
            f.write(head.encode("ascii"))
            f.write(pts.astype("<f4").tobytes())
    else:
        head = (f"ply\nformat ascii 1.0\nelement vertex {len(pts)}\n"
                "property double x\nproperty double y\nproperty double z\nend_header\n")
        with open(path, "w") as f:
            f.write(head)
            for p in pts:
                f.write(f"{p[0]:.17g} {p[1]:.17g} {p[2]:.17g}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--cases", type=int, default=6)
    ap.add_argument("--known", type=int, default=2, help="cases with a known scale, after the --cases ones")
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rng = np.random.default_rng(a.seed)
    plan = ["synthetic", "partial", "symmetric"]
    ident = {"rotation": np.eye(3).tolist(), "centre": [0.0, 0.0, 0.0]}
    cases = []
    for i in range(a.cases + a.known):
        if i < a.cases:
            family = plan[0] if i < a.cases // 2 else plan[1] if i < a.cases - a.cases // 6 else plan[2]
        else:
            family = ("metric", "known-scale")[(i - a.cases) % 2]
        seed = int(rng.integers(1, 2**31))
        crng = np.random.default_rng(seed)
        radius = radius_sym if family == "symmetric" else radius_asym
        model = sample_surface(crng, MODEL_POINTS, radius)
        diag = float(np.linalg.norm(model.max(0) - model.min(0)))
        view = None
        if family in ("partial", "metric"):
            view = crng.normal(size=3)
            view /= np.linalg.norm(view)
        scan_d = sample_surface(crng, SCAN_POINTS, radius, view)
        scan_d = scan_d + crng.normal(scale=NOISE_FRAC * diag, size=scan_d.shape)
        r = rotation(crng.normal(size=3), crng.uniform(0, MAX_DEG))
        s = float(crng.uniform(*SCALE_RANGE))
        if family == "metric":
            s = 1.0
        t = crng.uniform(-TRANS_FRAC, TRANS_FRAC, size=3) * diag
        scan = (scan_d - t) @ r / s  # rows: R^T (d - T) / s
        stem = f"{family}-{i:04d}"
        write_ply(os.path.join(a.out, stem + "-model.ply"), model, binary=True)
        write_ply(os.path.join(a.out, stem + "-scan.ply"), scan, binary=False)
        syms = [ident]
        if family == "symmetric":
            syms.append({"rotation": np.diag([-1.0, -1.0, 1.0]).tolist(), "centre": [0.0, 0.0, 0.0]})
        cases.append({"id": f"{family}/blob/{i:04d}", "family": family, "shape": "blob", "seed": seed,
                      "model": stem + "-model.ply", "scan": stem + "-scan.ply",
                      "truth": {"scale": s, "rotation": r.tolist(), "translation": t.tolist()},
                      "diag": diag, "reference_point": scan.mean(0).tolist(), "symmetries": syms,
                      "known_scale": s if family in ("metric", "known-scale") else None})
    suite = {"suite": "sample", "split": "test", "seed": a.seed,
             "tolerance": {"rotation_deg": 2.0, "translation_frac": 0.02, "scale_frac": 0.01}, "cases": cases}
    with open(os.path.join(a.out, "cases.json"), "w") as f:
        json.dump(suite, f, indent=1)
    print(f"wrote {len(cases)} cases to {a.out}")


if __name__ == "__main__":
    main()
