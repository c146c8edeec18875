"""Register a scan to a model with PF-ICP from Python and print the pose and its verdict.

    python examples/register.py [MODEL SCAN]

MODEL and SCAN are point-cloud files (PLY, PCD, XYZ, CSV). With Open3D installed they are
read as Open3D clouds and handed over as `np.asarray(pcd.points)`, as a lab's Open3D code
holds them; without it, `pficp.read_cloud` reads them. With no arguments, the example makes
its own: a bumpy part, and a scan of one side of it turned by 40 degrees and moved.
"""

import sys

import numpy as np

import pficp


def load(path):
    try:
        import open3d as o3d
    except ImportError:
        return pficp.read_cloud(path)
    pcd = o3d.io.read_point_cloud(str(path))
    return np.asarray(pcd.points)


def synthetic(seed=7):
    """A part with bumps on an ellipsoid (no symmetry), and one side of it as a scan."""
    rng = np.random.default_rng(seed)
    d = rng.normal(size=(4000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    bumps = 1 + 0.15 * np.sin(3 * d[:, 0]) * np.cos(2 * d[:, 1]) + 0.1 * d[:, 2] ** 2
    model = d * bumps[:, None] * [60.0, 35.0, 25.0]  # millimetres
    side = model[model[:, 2] > 0][:1500]
    a = np.radians(40)
    rotation = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    scan = (side - [5.0, -3.0, 2.0]) @ rotation + rng.normal(scale=0.1, size=side.shape)
    return model, np.ascontiguousarray(scan)


def main():
    if len(sys.argv) == 3:
        model, scan = load(sys.argv[1]), load(sys.argv[2])
        kwargs = {}
    else:
        model, scan = synthetic()
        kwargs = {"scale": 1.0}  # both in millimetres: the scale is known
    result = pficp.register(np.ascontiguousarray(model), np.ascontiguousarray(scan), **kwargs)
    np.set_printoptions(precision=4, suppress=True)
    print(f"verdict {result.verdict}" + (f": {'; '.join(result.reasons)}" if result.reasons else ""))
    print("transformation (scan to model):")
    print(result.transformation)
    print(f"scale {result.scale:.6f}, fitness {result.fitness:.3f}, inlier_rmse {result.inlier_rmse:.4g}")
    sigma = [f"{n} {np.degrees(s):.3g} deg" if n.startswith("r") else f"{n} {s:.3g}"
             for n, s in zip(result.covariance_order, result.sigma)]
    print("one sigma:", ", ".join(sigma))
    if result.alternatives:
        print(f"{len(result.alternatives)} other poses fit as well: do not act on this one alone")


if __name__ == "__main__":
    main()
