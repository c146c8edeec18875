#!/usr/bin/env python3
"""Write the PCD fixtures of host/tests/pcd_fixtures.rs with two independent writers.

    python3 host/tests/data/pcd/make_fixtures.py [OUTDIR]   (default: this file's folder)

Needs open3d==0.20.0 and pypcd4==1.5.1 (with numpy); not run by CI. Every NAME.pcd
comes with NAME.xyz: the points the reader must return, in file order, without the
invalid (NaN) points, each coordinate as Python's repr of the exact value stored in
the file (float32 values widened to float64), so the test compares bit for bit.
Seeded: the same versions write the same files.
"""

import os
import sys

import numpy as np
import open3d as o3d
from pypcd4 import Encoding, PointCloud

OUT = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
rng = np.random.default_rng(14)


def f32(a):
    """float64 values that float32 holds exactly."""
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def expect(name, xyz):
    """NAME.xyz: the valid points, exact."""
    xyz = np.asarray(xyz, dtype=np.float64)
    keep = ~np.isnan(xyz).any(axis=1)
    with open(os.path.join(OUT, name + ".xyz"), "w") as f:
        f.write(f"# {name}.pcd: {int(keep.sum())} valid points of {len(xyz)}\n")
        for p in xyz[keep]:
            f.write(" ".join(repr(float(v)) for v in p) + "\n")


def open3d_cloud(n, extras):
    pts = f32(rng.normal(scale=[2.0, 1.0, 0.5], size=(n, 3)) + [10.0, -3.0, 0.25])
    pc = o3d.geometry.PointCloud()
    pc.points = o3d.utility.Vector3dVector(pts)
    if extras:
        # Colours on a coarse grid and normals of a few directions: repeated bytes, so
        # the compressed file has LZF back references and not only literals.
        pc.colors = o3d.utility.Vector3dVector(rng.integers(0, 4, size=(n, 3)) / 3.0)
        pc.normals = o3d.utility.Vector3dVector(np.eye(3)[rng.integers(0, 3, size=n)])
    return pc, pts


# Open3D: x y z (F 4), ascii written with %.10g.
pc, pts = open3d_cloud(50, extras=False)
o3d.io.write_point_cloud(os.path.join(OUT, "open3d_ascii.pcd"), pc, write_ascii=True)
expect("open3d_ascii", pts)

# Open3D: x y z normal_x normal_y normal_z rgb, binary.
pc, pts = open3d_cloud(60, extras=True)
o3d.io.write_point_cloud(os.path.join(OUT, "open3d_binary_normals_rgb.pcd"), pc, write_ascii=False)
expect("open3d_binary_normals_rgb", pts)

# Open3D: the same fields, binary_compressed (LZF, field-major).
pc, pts = open3d_cloud(200, extras=True)
o3d.io.write_point_cloud(
    os.path.join(OUT, "open3d_compressed_normals_rgb.pcd"), pc, write_ascii=False, compressed=True
)
expect("open3d_compressed_normals_rgb", pts)

# pypcd4: fields of many types, x y z as F 4 between them, ascii (%.10f).
n = 40
xyz = f32(rng.uniform(0.5, 4.0, size=(n, 3)) * rng.choice([-1.0, 1.0], size=(n, 3)))
cols = [
    rng.integers(0, 65535, size=n).astype(np.uint16),
    xyz[:, 0].astype(np.float32),
    rng.integers(-100, 100, size=n).astype(np.int8),
    xyz[:, 1].astype(np.float32),
    rng.uniform(0, 1, size=n).astype(np.float64),
    xyz[:, 2].astype(np.float32),
    rng.integers(0, 2**31, size=n).astype(np.uint32),
]
fields = ("ring", "x", "flag", "y", "t", "z", "label")
types = (np.uint16, np.float32, np.int8, np.float32, np.float64, np.float32, np.uint32)
PointCloud.from_points(cols, fields, types).save(os.path.join(OUT, "pypcd4_fields_ascii.pcd"), Encoding.ASCII)
expect("pypcd4_fields_ascii", xyz)

# pypcd4: x y z as F 8 after a `_` padding field and an intensity, binary_compressed.
n = 120
xyz = rng.normal(size=(n, 3)) * 3.0
cols = [
    np.zeros(n, dtype=np.uint32),
    xyz[:, 0],
    xyz[:, 1],
    xyz[:, 2],
    rng.integers(0, 8, size=n).astype(np.float32),
]
fields = ("_", "x", "y", "z", "intensity")
types = (np.uint32, np.float64, np.float64, np.float64, np.float32)
PointCloud.from_points(cols, fields, types).save(
    os.path.join(OUT, "pypcd4_padding_f8_compressed.pcd"), Encoding.BINARY_COMPRESSED
)
expect("pypcd4_padding_f8_compressed", xyz)


def organised(name, encoding, dtype):
    """An organised 8 x 6 cloud (a depth image's points): NaN x y z where the sensor saw
    nothing, as PCL writes them, and one point with only z NaN."""
    w, h = 8, 6
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    z = 2.0 + 0.1 * rng.normal(size=(h, w))
    xyz = np.stack([(u - w / 2) * z / 10.0, (v - h / 2) * z / 10.0, z], axis=-1).reshape(-1, 3)
    xyz = np.asarray(xyz, dtype=dtype).astype(np.float64)
    invalid = rng.random(w * h) < 0.3
    xyz[invalid] = np.nan
    xyz[5, 2] = np.nan
    intensity = rng.uniform(0, 1, size=w * h).astype(np.float32)
    pc = PointCloud.from_points([xyz[:, 0], xyz[:, 1], xyz[:, 2], intensity], ("x", "y", "z", "intensity"),
                                (dtype, dtype, dtype, np.float32))
    pc.metadata = pc.metadata.derive(width=w, height=h)
    pc.save(os.path.join(OUT, name + ".pcd"), encoding)
    expect(name, xyz)


organised("pypcd4_organised_nan_binary", Encoding.BINARY, np.float32)
organised("pypcd4_organised_nan_compressed", Encoding.BINARY_COMPRESSED, np.float64)
print("wrote fixtures to", OUT)
