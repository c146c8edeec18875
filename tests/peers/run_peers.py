#!/usr/bin/env python3
"""Run peer registration methods on benchmark cases exported by the Rust tool.

    pficp eval --suite realistic --export DIR
    python3 tests/peers/run_peers.py DIR [--methods open3d,cpd,kiss-matcher] [--limit N] [--out peers.json]
    python3.10 tests/peers/run_peers.py DIR --methods teaser --out teaser.json   (the Python 3.10 venv)
    python3 tests/peers/run_peers.py --merge peers.json teaser.json [--out all.json]

DIR/cases.json lists the cases (format: tests/peers/README.md). Each case
has a model cloud, a scan cloud and the true pose d = s R m + T, which maps
a scan point m onto the model (d). Every method is run with the SCAN as the
moving cloud (source) and the MODEL as the fixed cloud (target), so the
returned pose is in the same convention as the truth.

Methods and their parameters (fixed for every case and family; no per-case
tuning; lengths are fractions of the case's "diag", the model's diagonal):

Known scale: a case's "known_scale" is null (or missing) when its family's
scale is unknown to the method, else the scale the user knows (1.0 for
metric families). Then every method except cpd multiplies the scan by it
first, registers rigidly and composes the scale back into the pose (the
scale error is then exactly that of known_scale). teaser and kiss-matcher
also pre-scale when the scale is unknown: by the ratio of RMS radii about
the centroids, model over scan, and then estimate the scale (TEASER++) and
refine it (ICP with scaling). cpd ignores known_scale.

open3d -- Open3D's global registration tutorial: RANSAC on FPFH feature
    correspondences, then ICP point-to-point, both with scale estimation.
      voxel   v = OPEN3D_VOXEL_FRAC * diag = 0.05 diag, the same voxel for
              scan and model (the scale is unknown beforehand, so the scan is
              not rescaled; FPFH is not scale invariant, which is part of
              what is measured)
      normals KDTreeSearchParamHybrid(radius = 2 v, max_nn = 30)
      FPFH    KDTreeSearchParamHybrid(radius = 5 v, max_nn = 100)
      RANSAC  registration_ransac_based_on_feature_matching, mutual_filter
              True, max_correspondence_distance 1.5 v,
              TransformationEstimationPointToPoint(with_scaling=True),
              ransac_n 3, RANSACConvergenceCriteria(100000, 0.999), checkers
              CorrespondenceCheckerBasedOnDistance(1.5 v) and
              CorrespondenceCheckerBasedOnEdgeLength(t) with t = 0.63
              instead of the tutorial's 0.9. That checker keeps a triple only
              if every model edge / scan edge ratio is in [t, 1/t], i.e. it
              bounds the scale. 0.9 (unit scale +-10 %) would reject every
              correct triple for scales outside [0.9, 1.11]; without the
              checker RANSAC with scaling picks the degenerate s ~ 0 pose
              (all scan points collapse onto one model point: fitness 1,
              rmse 0), seen on the sample. t = 0.9 * 0.7 keeps the
              tutorial's 10 % slack beyond the benchmark's scale range
              0.7..1.3 (admits 0.63..1.59): a global prior, the same for
              every case, that the benchmark's documentation states.
              Open3D draws each RANSAC triple WITH replacement (Open3D source,
              Registration.cpp: corres[rand_gen()] per element), so a triple
              can be one correspondence three times: the edge checker passes
              it (0 < 0 is false), the scaled fit collapses (A = 0) and the
              collapsed pose wins on fitness 1 / rmse 0. Such a draw comes
              about once per N^2 iterations (N correspondences, ~150 here),
              so it happens in a sizeable share of runs. Guard: if RANSAC's
              scale det(A)^(1/3) is outside [t, 1/t] (which the edge checker
              means to forbid), RANSAC is run again with seed + k, at most
              OPEN3D_RANSAC_ATTEMPTS = 5 runs in all (the last result is
              kept either way; the retries are timed; info.ransac_attempts
              records how many runs were needed).
      ICP     registration_icp on the full-resolution clouds (not the voxel
              down-sampled ones), max_correspondence_distance 0.5 v,
              TransformationEstimationPointToPoint(with_scaling=True),
              ICPConvergenceCriteria(max_iteration=100) (the default 30 is
              short for the slower scale updates; relative fitness / rmse
              defaults 1e-6), started from the RANSAC result.
      RNG     o3d.utility.random.seed(case seed & 0x7FFFFFFF) before each case
              (Open3D takes a signed 32-bit seed; exported seeds are 64-bit).
      pose    Open3D returns a 4x4 [[A, t], [0, 1]] with A = s R:
              s = cbrt(det A), R = nearest rotation to A / s (SVD), T = t.
      known scale k: the scan is multiplied by k; RANSAC and ICP are rigid
              (with_scaling False) and RANSAC's edge checker is the
              tutorial's 0.9 (OPEN3D_EDGE_SIMILARITY_KNOWN; no scale to
              admit, and no collapse to guard against); the pose's A is
              multiplied by k. The unknown-scale path is as above.

teaser -- FPFH correspondences, TEASER++ (cmeel-teaser-plusplus 2.0's
      teaserpp_python; CPython 3.10 and numpy < 2 only), then Open3D ICP.
      pre-scale k = known_scale, else RMS radius (model) / RMS radius (scan)
      features the open3d peer's: voxel v = 0.05 diag, normals 2 v / 30,
              FPFH 5 v / 100, on k * scan and on the model.
      correspondences  Open3D's correspondences_from_features(mutual_filter
              True): mutual nearest neighbours in FPFH space, the same set
              as the open3d peer's RANSAC builds (Open3D keeps every nearest
              neighbour instead when fewer than 10 % are mutual).
      TEASER++ RobustRegistrationSolver.Params() defaults except
              noise_bound = TEASER_NOISE_BOUND * v = v (the default 0.01 is
              absolute; TEASER++'s FPFH example uses the voxel size) and
              estimate_scaling = True only when the scale is unknown (the
              default True; False when known). Defaults kept: cbar2 1,
              GNC-TLS rotation (factor 1.4, 100 iterations, cost threshold
              1e-6), PMC_EXACT max clique (time limit 3600 s), chain TIM graph.
              Its C++ progress messages on stdout are sent to /dev/null.
      ICP     as the open3d peer's (0.5 v, point-to-point, 100 iterations)
              from TEASER++'s pose, with scaling when the scale is unknown,
              rigid when known. Pose = ICP's with A multiplied by k.

kiss-matcher -- KISS-Matcher 1.0.2 (rigid global registration), then Open3D ICP.
      pre-scale k as teaser's.
      KISS-Matcher sees k * scan / diag and model / diag (unit diagonal,
              because its config has absolute thresholds: a voxel below 5e-3
              is refused and noise bounds above 1.0 are clamped) with
              KISSMatcherConfig(voxel_size = 0.05), i.e. v; every other
              setting its default (normal radius 3 v, FPFH radius 5 v,
              ROBIN noise bound gain 1.0, solver noise bound gain 0.75,
              ratio test on, no linearity filter, at most 5000
              correspondences). Its translation is multiplied back by diag.
      ICP     as teaser's, from KISS-Matcher's pose (its identity when it
              reports an invalid solution; info.kiss_valid records it).

cpd -- pycpd's RigidRegistration (Coherent Point Drift, rigid + scale):
      X (fixed) = model, Y (moving) = scan.
      w = CPD_W = 0.1: weight of the uniform outlier component (the scan
              and model are sampled independently and scans may be partial,
              so a non-zero outlier weight is needed; 0.1 is a small value).
      max_iterations = CPD_MAX_ITER = 100, tolerance = pycpd default (1e-3
              on the change of its objective), sigma2 = pycpd default
              (mean squared distance of all pairs), initial pose identity.
      points  pycpd is dense (M x N probability matrix, and its sigma2
              initialisation builds an M x N x 3 array), so clouds are
              randomly sub-sampled (numpy default_rng(case seed), without
              replacement) to at most CPD_MAX_MODEL = 2000 model points and
              CPD_MAX_SCAN = 1500 scan points. Sub-sampling is timed.
      pose    pycpd moves Y as row vectors: TY = s * Y @ R + t, i.e. for a
              column vector m: s R^T m + t. So (s, R^T, t) in d = s R m + T.

Scoring (the Rust tool's rule, see score()): for each symmetry g = (G, c) of
the model the symmetric truth is p -> G (s_t R_t p + T_t - c) + c. Rotation
error = angle of R_e^T G R_t [deg], translation error = |est(p_ref) -
truth_g(p_ref)| / diag with p_ref = case "reference_point", scale error =
|s_e / s_t - 1|. Success if for some g all three are within the tolerance
in cases.json; reported errors are those for the g of smallest rotation error
(among the successful g if any, as the Rust tool does).

Timing: wall-clock seconds of each method's registration only (from numpy
arrays in memory to the pose; includes down-sampling, normals, features),
not file reading or scoring.

Each case also gets "truth_residual_frac": the median distance from the
truth-mapped scan to the nearest model point over diag (needs scipy), a
check that the export's truth really maps scan onto model. The pseudo-method
"truth" (--methods truth) returns the truth itself and must score zero.

--limit N takes N cases spread evenly over the file's order (indices
floor(i * len / N)), so every family in a family-grouped file is sampled;
--first takes the first N instead.

Threads: --threads N (default 1) bounds Open3D (o3d.utility.set_max_threads)
and BLAS and OpenMP (OMP/OPENBLAS/MKL_NUM_THREADS, unless already set; TEASER++'s
max clique uses OpenMP). With more than
one thread Open3D's RANSAC is not repeatable even with a fixed seed: its
TBB workers share one random generator, so which draws each worker gets
varies from run to run. One thread makes runs repeat and times a single
core; 0 lets Open3D use every core.

Self-check: `run_peers.py --selftest` checks the scoring rule, the
pre-scaling helpers, the pycpd pose conversion on a synthetic case with a
known pose, and each installed Open3D-based peer (open3d, teaser,
kiss-matcher) on a synthetic surface with the scale unknown and known.
"""

import argparse
import json
import math
import os
import statistics
import sys
import time


def _peek_threads(argv):
    """The --threads value (default 1), read before numpy is imported so BLAS sees it."""
    for i, a in enumerate(argv):
        if a == "--threads" and i + 1 < len(argv):
            return argv[i + 1]
        if a.startswith("--threads="):
            return a.split("=", 1)[1]
    return "1"


if __name__ == "__main__" and _peek_threads(sys.argv) != "0":
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, _peek_threads(sys.argv))

import numpy as np  # noqa: E402

# ---------------------------------------------------------------- parameters
OPEN3D_VOXEL_FRAC = 0.05      # voxel size v as a fraction of the model diagonal
OPEN3D_NORMAL_RADIUS = 2.0    # x v
OPEN3D_NORMAL_MAX_NN = 30
OPEN3D_FPFH_RADIUS = 5.0      # x v
OPEN3D_FPFH_MAX_NN = 100
OPEN3D_RANSAC_DIST = 1.5      # x v, max correspondence distance and distance checker
OPEN3D_EDGE_SIMILARITY = 0.63  # edge-length checker: scale admitted in [0.63, 1/0.63]
OPEN3D_EDGE_SIMILARITY_KNOWN = 0.9  # the tutorial's value, for rigid RANSAC on a pre-scaled scan
OPEN3D_RANSAC_ATTEMPTS = 5    # RANSAC runs at most, while its scale is outside that range
OPEN3D_RANSAC_N = 3
OPEN3D_RANSAC_MAX_ITER = 100000
OPEN3D_RANSAC_CONFIDENCE = 0.999
OPEN3D_ICP_DIST = 0.5         # x v
OPEN3D_ICP_MAX_ITER = 100

CPD_W = 0.1
CPD_MAX_ITER = 100
CPD_MAX_MODEL = 2000
CPD_MAX_SCAN = 1500

TEASER_NOISE_BOUND = 1.0      # x v (TEASER++'s default is an absolute 0.01)
# KISS-Matcher: voxel_size = OPEN3D_VOXEL_FRAC on clouds divided by diag (= v), the rest its defaults

ALL_METHODS = ("open3d", "cpd")


# ---------------------------------------------------------------- PLY reading
_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}


def read_ply_xyz(path):
    """Return the x, y, z of the `vertex` element of a PLY file as (N, 3) float64.

    Supports `ascii 1.0` and `binary_little_endian 1.0`; other elements and
    properties (including list properties) are skipped.
    """
    with open(path, "rb") as f:
        if f.readline().strip() != b"ply":
            raise ValueError(f"{path}: not a PLY file")
        fmt = None
        elements = []  # (name, count, [(prop name, dtype or ('list', count dtype, item dtype))])
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            words = line.decode("ascii", "replace").split()
            if not words or words[0] in ("comment", "obj_info"):
                continue
            if words[0] == "end_header":
                break
            if words[0] == "format":
                fmt = words[1]
                if words[2] != "1.0":
                    raise ValueError(f"{path}: PLY version {words[2]}")
            elif words[0] == "element":
                elements.append((words[1], int(words[2]), []))
            elif words[0] == "property":
                if words[1] == "list":
                    elements[-1][2].append((words[4], ("list", _PLY_TYPES[words[2]], _PLY_TYPES[words[3]])))
                else:
                    elements[-1][2].append((words[2], _PLY_TYPES[words[1]]))
        if fmt not in ("ascii", "binary_little_endian"):
            raise ValueError(f"{path}: unsupported PLY format {fmt}")
        data = f.read()

    pos = 0
    if fmt == "ascii":
        lines = data.decode("ascii").splitlines()
        lines = [l for l in lines if l.strip()]
    for name, count, props in elements:
        if fmt == "ascii":
            rows = lines[pos:pos + count]
            pos += count
            if name == "vertex":
                names = [p[0] for p in props]
                if any(isinstance(p[1], tuple) for p in props):
                    raise ValueError(f"{path}: list property in vertex element")
                ix = [names.index(a) for a in ("x", "y", "z")]
                arr = np.array([r.split() for r in rows], dtype=np.float64).reshape(count, len(props))
                return arr[:, ix]
        else:
            if all(not isinstance(p[1], tuple) for p in props):
                dt = np.dtype([(p[0], "<" + p[1]) for p in props])
                block = np.frombuffer(data, dtype=dt, count=count, offset=pos)
                pos += count * dt.itemsize
                if name == "vertex":
                    return np.stack([block[a].astype(np.float64) for a in ("x", "y", "z")], axis=1)
            else:
                if name == "vertex":
                    raise ValueError(f"{path}: list property in vertex element")
                for _ in range(count):  # skip an element with list properties
                    for _, t in props:
                        if isinstance(t, tuple):
                            n = int(np.frombuffer(data, "<" + t[1], 1, pos)[0])
                            pos += np.dtype(t[1]).itemsize + n * np.dtype(t[2]).itemsize
                        else:
                            pos += np.dtype(t).itemsize
    raise ValueError(f"{path}: no vertex element")


# ---------------------------------------------------------------- scoring
def rotation_angle_deg(r):
    """Angle of a rotation matrix in degrees: acos((trace - 1) / 2), clamped."""
    c = (np.trace(r) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def score(est, case, tol):
    """Score an estimate (s, R, T) against a case's truth and symmetries.

    Returns a dict with `success` (some symmetry within all three
    tolerances) and the errors and index of the symmetry reported: the one
    of smallest rotation error among the successful symmetries if any, else
    among all (the Rust tool's choice; they differ from "smallest rotation
    error" only when that g fails on translation or scale and another passes).
    """
    s_e, r_e, t_e = est
    truth = case["truth"]
    s_t = float(truth["scale"])
    r_t = np.asarray(truth["rotation"], float)
    t_t = np.asarray(truth["translation"], float)
    p = np.asarray(case["reference_point"], float)
    diag = float(case["diag"])
    est_p = s_e * r_e @ p + t_e
    truth_p = s_t * r_t @ p + t_t
    syms = case.get("symmetries") or [{"rotation": np.eye(3).tolist(), "centre": [0, 0, 0]}]
    best = None
    for k, g in enumerate(syms):
        gm = np.asarray(g["rotation"], float)
        c = np.asarray(g["centre"], float)
        e = {
            "rotation_deg": rotation_angle_deg(r_e.T @ (gm @ r_t)),
            "translation_frac": float(np.linalg.norm(est_p - (gm @ (truth_p - c) + c)) / diag),
            "scale_frac": abs(s_e / s_t - 1.0),
            "symmetry": k,
        }
        e["success"] = (e["rotation_deg"] <= tol["rotation_deg"]
                        and e["translation_frac"] <= tol["translation_frac"]
                        and e["scale_frac"] <= tol["scale_frac"])
        # as host/src/eval/realistic.rs::score: a successful g first, then the smallest rotation error
        if (best is None or (e["success"] and not best["success"])
                or (e["success"] == best["success"] and e["rotation_deg"] < best["rotation_deg"])):
            best = e
    return best


def nearest_rotation(a):
    """The rotation matrix nearest to `a` (Frobenius), via SVD."""
    u, _, vt = np.linalg.svd(a)
    d = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, d]) @ vt


def similarity_from_matrix(m):
    """Split a 4x4 [[s R, t], [0, 1]] into (s, R, t)."""
    a = np.asarray(m, float)[:3, :3]
    s = float(np.cbrt(np.linalg.det(a)))
    return s, nearest_rotation(a / s), np.asarray(m, float)[:3, 3].copy()


# ---------------------------------------------------------------- methods
def known_scale(case):
    """The case's "known_scale": None when the family's scale is unknown (or the key is missing)."""
    k = case.get("known_scale")
    return None if k is None else float(k)


def rms_radius(points):
    """Root-mean-square distance of the points from their centroid."""
    p = np.asarray(points, float)
    return float(np.sqrt(np.mean(np.sum((p - p.mean(0)) ** 2, axis=1))))


def prescale(model, scan, case):
    """(k, known): the factor the scan is multiplied by before a method runs.

    The case's known_scale when it has one (known = True: the method then
    registers rigidly), else the ratio of RMS radii about the centroids, model
    over scan (known = False: a first guess that the method refines).
    """
    k = known_scale(case)
    if k is not None:
        return k, True
    return rms_radius(model) / rms_radius(scan), False


def compose_prescale(m, k):
    """A 4x4 pose found for the pre-scaled scan k * m, as a pose for the scan m itself."""
    out = np.asarray(m, float).copy()
    out[:3, :3] = out[:3, :3] * k
    return out


def _o3d_cloud(points):
    import open3d as o3d
    pc = o3d.geometry.PointCloud()
    pc.points = o3d.utility.Vector3dVector(np.ascontiguousarray(points, dtype=np.float64))
    return pc


def _o3d_features(pc, v):
    """The open3d peer's down-sampling, normals and FPFH: (down-sampled cloud, FPFH)."""
    import open3d as o3d
    reg = o3d.pipelines.registration
    down = pc.voxel_down_sample(v)
    down.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(
        radius=OPEN3D_NORMAL_RADIUS * v, max_nn=OPEN3D_NORMAL_MAX_NN))
    fpfh = reg.compute_fpfh_feature(down, o3d.geometry.KDTreeSearchParamHybrid(
        radius=OPEN3D_FPFH_RADIUS * v, max_nn=OPEN3D_FPFH_MAX_NN))
    return down, fpfh


def _o3d_icp(source, target, v, init, with_scaling):
    """The open3d peer's ICP: point-to-point on the full clouds, 0.5 v, 100 iterations."""
    import open3d as o3d
    reg = o3d.pipelines.registration
    return reg.registration_icp(
        source, target, OPEN3D_ICP_DIST * v, np.asarray(init, float),
        reg.TransformationEstimationPointToPoint(with_scaling=with_scaling),
        reg.ICPConvergenceCriteria(max_iteration=OPEN3D_ICP_MAX_ITER))


def _finite_pose(m, what):
    m = np.asarray(m, float)
    if not np.all(np.isfinite(m)):
        raise ValueError(f"non-finite {what} transformation")
    return m


def run_open3d(model, scan, case):
    """Open3D FPFH + RANSAC, then ICP. Returns (s, R, T, info).

    Unknown scale: both with scaling, on the scan as given. Known scale k: the
    scan is multiplied by k first, RANSAC and ICP are rigid (the tutorial's
    edge checker 0.9), and k is composed back into the pose.
    """
    import open3d as o3d
    reg = o3d.pipelines.registration
    o3d.utility.random.seed(int(case.get("seed", 0)) & 0x7FFFFFFF)
    v = OPEN3D_VOXEL_FRAC * float(case["diag"])
    k = known_scale(case)
    scaled = k is not None
    source, target = _o3d_cloud(scan if k is None else k * scan), _o3d_cloud(model)
    src_down, src_fpfh = _o3d_features(source, v)
    tgt_down, tgt_fpfh = _o3d_features(target, v)
    dist = OPEN3D_RANSAC_DIST * v
    edge = OPEN3D_EDGE_SIMILARITY_KNOWN if scaled else OPEN3D_EDGE_SIMILARITY
    lo, hi = OPEN3D_EDGE_SIMILARITY, 1.0 / OPEN3D_EDGE_SIMILARITY
    for attempt in range(OPEN3D_RANSAC_ATTEMPTS):
        ransac = reg.registration_ransac_based_on_feature_matching(
            src_down, tgt_down, src_fpfh, tgt_fpfh, True, dist,
            reg.TransformationEstimationPointToPoint(with_scaling=not scaled),
            OPEN3D_RANSAC_N,
            [reg.CorrespondenceCheckerBasedOnEdgeLength(edge),
             reg.CorrespondenceCheckerBasedOnDistance(dist)],
            reg.RANSACConvergenceCriteria(OPEN3D_RANSAC_MAX_ITER, OPEN3D_RANSAC_CONFIDENCE))
        a = np.asarray(ransac.transformation)[:3, :3]
        s_ransac = float(np.cbrt(np.linalg.det(a)))
        if scaled or lo <= s_ransac <= hi:  # rigid: det A = 1, no collapse to guard against
            break
        # degenerate (see OPEN3D_RANSAC_ATTEMPTS): draw again with the next seed
        o3d.utility.random.seed((int(case.get("seed", 0)) + attempt + 1) & 0x7FFFFFFF)
    icp = _o3d_icp(source, target, v, ransac.transformation, with_scaling=not scaled)
    m = _finite_pose(icp.transformation, "ICP")
    if scaled:
        m = compose_prescale(m, k)
    info = {"known_scale": k, "ransac_attempts": attempt + 1, "ransac_scale": s_ransac,
            "ransac_fitness": ransac.fitness, "ransac_rmse": ransac.inlier_rmse,
            "icp_fitness": icp.fitness, "icp_rmse": icp.inlier_rmse,
            "scan_down": len(src_down.points), "model_down": len(tgt_down.points)}
    return similarity_from_matrix(m) + (info,)


class _StdoutToDevnull:
    """Send file descriptor 1 to /dev/null meanwhile (TEASER++ prints its progress there from C++)."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, 1)
        os.close(null)

    def __exit__(self, *exc):
        os.dup2(self.saved, 1)
        os.close(self.saved)


def _teaser_solver(v, estimate_scaling):
    import teaserpp_python as tpp
    params = tpp.RobustRegistrationSolver.Params()
    params.noise_bound = TEASER_NOISE_BOUND * v
    params.estimate_scaling = estimate_scaling
    return tpp.RobustRegistrationSolver(params)


def run_teaser(model, scan, case):
    """FPFH correspondences (as the open3d peer), TEASER++, then Open3D ICP. Returns (s, R, T, info).

    The scan is pre-scaled (known scale, or the RMS-radius ratio); TEASER++
    estimates the scale only when it is unknown, and ICP then runs with
    scaling; with a known scale both are rigid.
    """
    import open3d as o3d
    reg = o3d.pipelines.registration
    o3d.utility.random.seed(int(case.get("seed", 0)) & 0x7FFFFFFF)
    v = OPEN3D_VOXEL_FRAC * float(case["diag"])
    k, known = prescale(model, scan, case)
    source, target = _o3d_cloud(k * scan), _o3d_cloud(model)
    src_down, src_fpfh = _o3d_features(source, v)
    tgt_down, tgt_fpfh = _o3d_features(target, v)
    corres = np.asarray(reg.correspondences_from_features(src_fpfh, tgt_fpfh, True))
    if len(corres) < 3:
        raise ValueError(f"{len(corres)} FPFH correspondences")
    src = np.ascontiguousarray(np.asarray(src_down.points)[corres[:, 0]].T)
    dst = np.ascontiguousarray(np.asarray(tgt_down.points)[corres[:, 1]].T)
    solver = _teaser_solver(v, estimate_scaling=not known)
    with _StdoutToDevnull():
        solver.solve(src, dst)
    sol = solver.getSolution()  # the Python binding has no `valid` flag
    init = np.eye(4)
    init[:3, :3] = float(sol.scale) * np.asarray(sol.rotation, float)
    init[:3, 3] = np.asarray(sol.translation, float).reshape(3)
    _finite_pose(init, "TEASER++")
    icp = _o3d_icp(source, target, v, init, with_scaling=not known)
    m = compose_prescale(_finite_pose(icp.transformation, "ICP"), k)
    info = {"known_scale": known_scale(case), "prescale": k, "correspondences": len(corres),
            # Open3D keeps every nearest neighbour when fewer than 10 % are mutual
            "correspondences_not_mutual": bool(len(corres) == len(src_down.points)),
            "teaser_scale": float(sol.scale),
            "teaser_max_clique": len(solver.getInlierMaxClique()),
            "teaser_rotation_inliers": len(solver.getRotationInliers()),
            "teaser_translation_inliers": len(solver.getTranslationInliers()),
            "icp_fitness": icp.fitness, "icp_rmse": icp.inlier_rmse,
            "scan_down": len(src_down.points), "model_down": len(tgt_down.points)}
    return similarity_from_matrix(m) + (info,)


def run_kiss_matcher(model, scan, case):
    """KISS-Matcher (rigid), then Open3D ICP. Returns (s, R, T, info).

    The scan is pre-scaled (known scale, or the RMS-radius ratio) and
    KISS-Matcher registers it rigidly; ICP then runs with scaling when the
    scale is unknown, rigid when it is known. KISS-Matcher sees both clouds
    divided by diag (unit diagonal): its config has absolute thresholds (a
    voxel of at least 5e-3, noise bounds clamped at 1.0).
    """
    import open3d as o3d
    import kiss_matcher as km
    diag = float(case["diag"])
    v = OPEN3D_VOXEL_FRAC * diag
    k, known = prescale(model, scan, case)
    src = np.ascontiguousarray(k * scan / diag, dtype=np.float32)
    tgt = np.ascontiguousarray(model / diag, dtype=np.float32)
    matcher = km.KISSMatcher(km.KISSMatcherConfig(voxel_size=OPEN3D_VOXEL_FRAC))
    sol = matcher.estimate(list(src), list(tgt))
    init = np.eye(4)
    init[:3, :3] = np.asarray(sol.rotation, float)
    init[:3, 3] = np.asarray(sol.translation, float).reshape(3) * diag
    _finite_pose(init, "KISS-Matcher")
    o3d.utility.random.seed(int(case.get("seed", 0)) & 0x7FFFFFFF)
    source, target = _o3d_cloud(k * scan), _o3d_cloud(model)
    icp = _o3d_icp(source, target, v, init, with_scaling=not known)
    if not np.all(np.isfinite(np.asarray(icp.transformation))):
        # seen when KISS-Matcher returns its invalid solution (identity) and ICP then has ~1 correspondence
        raise ValueError(f"non-finite ICP transformation (KISS-Matcher valid={bool(sol.valid)}, "
                         f"{len(matcher.get_initial_correspondences())} initial correspondences, "
                         f"ICP {len(icp.correspondence_set)} correspondences)")
    m = compose_prescale(np.asarray(icp.transformation), k)
    info = {"known_scale": known_scale(case), "prescale": k, "kiss_valid": bool(sol.valid),
            "kiss_rotation_inliers": int(matcher.get_num_rotation_inliers()),
            "kiss_final_inliers": int(matcher.get_num_final_inliers()),
            "kiss_initial_correspondences": len(matcher.get_initial_correspondences()),
            "icp_fitness": icp.fitness, "icp_rmse": icp.inlier_rmse}
    return similarity_from_matrix(m) + (info,)


def cpd_pose(s, r, t):
    """pycpd's (s, R, t) (row vectors: s * Y @ R + t) as (s, R', T) with d = s R' m + T."""
    return float(s), nearest_rotation(np.asarray(r, float).T), np.asarray(t, float).reshape(3)


def run_cpd(model, scan, case):
    """pycpd RigidRegistration (X = model, Y = scan). Returns (s, R, T)."""
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SyntaxWarning)  # pycpd uses `is not` on ints
        from pycpd import RigidRegistration
    rng = np.random.default_rng(int(case.get("seed", 0)))

    def cap(points, n):
        if len(points) <= n:
            return points
        return points[rng.choice(len(points), n, replace=False)]

    x = np.ascontiguousarray(cap(model, CPD_MAX_MODEL))
    y = np.ascontiguousarray(cap(scan, CPD_MAX_SCAN))
    cpd = RigidRegistration(X=x, Y=y, w=CPD_W, max_iterations=CPD_MAX_ITER)
    _, (s, r, t) = cpd.register()
    return cpd_pose(s, r, t) + ({"iterations": cpd.iteration, "sigma2": float(cpd.sigma2)},)


def run_truth(model, scan, case):
    """Not a peer: returns the truth itself (must score zero error; checks scoring)."""
    t = case["truth"]
    return float(t["scale"]), np.asarray(t["rotation"], float), np.asarray(t["translation"], float), {}


METHOD_FUNCS = {"open3d": run_open3d, "cpd": run_cpd, "teaser": run_teaser,
                "kiss-matcher": run_kiss_matcher, "truth": run_truth}


def truth_residual(model, scan, case):
    """Median distance from the truth-mapped scan points to their nearest model point, over diag.

    A check of the export itself: it is small (about the noise level) when the
    truth really maps the scan onto the model, large when a convention is off.
    """
    from scipy.spatial import cKDTree
    s, r, t, _ = run_truth(model, scan, case)
    d, _ = cKDTree(model).query(s * scan @ r.T + t)
    return float(np.median(d) / float(case["diag"]))


# ---------------------------------------------------------------- driver
def pick_cases(cases, limit, first):
    if limit is None or limit >= len(cases):
        return cases
    if first:
        return cases[:limit]
    return [cases[(i * len(cases)) // limit] for i in range(limit)]


def summarise(results, methods):
    """Per family (plus "all"): successes, cases, rate and median seconds per method."""
    families = sorted({r["family"] for r in results})
    summary = {}
    for fam in families + ["all"]:
        rows = [r for r in results if fam == "all" or r["family"] == fam]
        summary[fam] = {}
        for m in methods:
            runs = [r["methods"][m] for r in rows if m in r["methods"]]
            ok = sum(1 for x in runs if x["success"])
            secs = [x["seconds"] for x in runs if x["seconds"] is not None]
            summary[fam][m] = {
                "successes": ok,
                "cases": len(runs),
                "rate": ok / len(runs) if runs else None,
                "median_seconds": statistics.median(secs) if secs else None,
            }
    return summary


def format_table(summary, methods):
    head = ["family"]
    for m in methods:
        head += [f"{m} success", f"{m} median s"]
    rows = []
    for fam, per in summary.items():
        row = [fam]
        for m in methods:
            x = per[m]
            pct = 100.0 * x["rate"] if x["rate"] is not None else 0.0
            row.append(f"{x['successes']}/{x['cases']} ({pct:.0f}%)")
            row.append("-" if x["median_seconds"] is None else f"{x['median_seconds']:.3f}")
        rows.append(row)
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    fmt = lambda r: "  ".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
    lines = [fmt(head), "  ".join("-" * w for w in widths)]
    for r in rows:
        if r[0] == "all":
            lines.append("  ".join("-" * w for w in widths))
        lines.append(fmt(r))
    return "\n".join(lines)


def prepare(methods, threads):
    """Import the methods' packages (so that imports are not timed) and bound threads."""
    if {"open3d", "teaser", "kiss-matcher"} & set(methods):
        import open3d as o3d
        o3d.utility.set_max_threads(threads)
        o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    if "teaser" in methods:
        import teaserpp_python  # noqa: F401
    if "kiss-matcher" in methods:
        import kiss_matcher  # noqa: F401
    if "cpd" in methods:
        import warnings
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SyntaxWarning)
            import pycpd  # noqa: F401


def run(directory, methods, limit=None, first=False, out=None, verbose=True, threads=1):
    prepare(methods, threads)
    with open(os.path.join(directory, "cases.json")) as f:
        suite = json.load(f)
    tol = suite["tolerance"]
    cases = pick_cases(suite["cases"], limit, first)
    results = []
    for i, case in enumerate(cases):
        model = read_ply_xyz(os.path.join(directory, case["model"]))
        scan = read_ply_xyz(os.path.join(directory, case["scan"]))
        entry = {"id": case["id"], "family": case.get("family", "?"), "shape": case.get("shape"),
                 "held_out": case.get("held_out"),
                 "model_points": len(model), "scan_points": len(scan), "methods": {}}
        try:
            entry["truth_residual_frac"] = truth_residual(model, scan, case)
        except ImportError:
            entry["truth_residual_frac"] = None
        for m in methods:
            t0 = time.perf_counter()
            try:
                *est, info = METHOD_FUNCS[m](model, scan, case)
                secs = time.perf_counter() - t0
                e = score(est, case, tol)
                e["seconds"] = secs
                e["info"] = info
                e["estimate"] = {"scale": est[0], "rotation": est[1].tolist(), "translation": est[2].tolist()}
            except Exception as exc:  # a method that throws counts as a failure
                e = {"success": False, "seconds": time.perf_counter() - t0, "error": repr(exc)}
            entry["methods"][m] = e
        results.append(entry)
        if verbose:
            parts = []
            for m in methods:
                e = entry["methods"][m]
                if "error" in e:
                    parts.append(f"{m}: ERROR {e['error']}")
                else:
                    parts.append(f"{m}: {'ok  ' if e['success'] else 'FAIL'} {e['rotation_deg']:7.2f} deg "
                                 f"{100 * e['translation_frac']:6.2f}% {100 * e['scale_frac']:6.2f}% {e['seconds']:6.2f}s")
            res = entry["truth_residual_frac"]
            res = "" if res is None else f"(truth residual {100 * res:.2f}%)  "
            print(f"[{i + 1}/{len(cases)}] {case['id']} {res}" + "  |  ".join(parts), file=sys.stderr, flush=True)
    summary = summarise(results, methods)
    report = {"suite": suite.get("suite"), "split": suite.get("split"), "seed": suite.get("seed"),
              "tolerance": tol, "methods": list(methods), "threads": threads,
              "parameters": parameters(), "versions": versions(methods),
              "cases": results, "summary": summary}
    if out:
        with open(out, "w") as f:
            json.dump(report, f, indent=1)
    return report


def parameters():
    return {k: v for k, v in globals().items() if k.startswith(("OPEN3D_", "CPD_", "TEASER_"))}


def versions(methods):
    v = {"python": sys.version.split()[0], "numpy": np.__version__}
    from importlib.metadata import version
    if {"open3d", "teaser", "kiss-matcher"} & set(methods):
        import open3d
        v["open3d"] = open3d.__version__
    if "cpd" in methods:
        v["pycpd"] = version("pycpd")
    if "teaser" in methods:
        v["cmeel-teaser-plusplus"] = version("cmeel-teaser-plusplus")
    if "kiss-matcher" in methods:
        v["kiss-matcher"] = version("kiss-matcher")
    return v


def merge(paths, out=None):
    """Merge --out files of runs on the same cases (e.g. one per venv) into one report.

    Cases are matched by id; each file adds its methods' entries. The merged
    "versions" keeps each file's (python, numpy and the methods' packages),
    keyed by method.
    """
    reports = [json.load(open(p)) for p in paths]
    base = reports[0]
    methods, cases, order = [], {}, []
    versions_by_method = {}
    for rep in reports:
        for key in ("suite", "split", "seed", "tolerance"):
            if rep.get(key) != base.get(key):
                raise ValueError(f"{key} differs between the files to merge")
        for m in rep["methods"]:
            if m in methods:
                raise ValueError(f"method {m} is in more than one file")
            methods.append(m)
            versions_by_method[m] = rep.get("versions")
        for c in rep["cases"]:
            if c["id"] not in cases:
                cases[c["id"]] = {k: v for k, v in c.items() if k != "methods"} | {"methods": {}}
                order.append(c["id"])
            cases[c["id"]]["methods"].update(c["methods"])
    results = [cases[i] for i in order]
    report = {"suite": base.get("suite"), "split": base.get("split"), "seed": base.get("seed"),
              "tolerance": base["tolerance"], "methods": methods,
              "threads": {m: rep.get("threads") for rep in reports for m in rep["methods"]},
              "parameters": base.get("parameters"), "versions": versions_by_method,
              "merged_from": list(paths), "cases": results, "summary": summarise(results, methods)}
    if out:
        with open(out, "w") as f:
            json.dump(report, f, indent=1)
    return report


# ---------------------------------------------------------------- self-test
def random_rotation(rng, max_deg=180.0, exact_deg=None):
    """A rotation about a random axis by a uniform angle in [0, max_deg] (or exactly exact_deg)."""
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    ang = math.radians(rng.uniform(0, max_deg) if exact_deg is None else exact_deg)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(ang) * k + (1 - math.cos(ang)) * k @ k


def selftest():
    rng = np.random.default_rng(7)
    tol = {"rotation_deg": 2.0, "translation_frac": 0.02, "scale_frac": 0.01}
    r_t, s_t, t_t = random_rotation(rng, 60), 0.9, np.array([0.1, -0.2, 0.3])
    # 180 deg about z through c: a symmetry of some model
    g, c = np.diag([-1.0, -1.0, 1.0]), np.array([0.05, 0.02, 0.0])
    case = {"truth": {"scale": s_t, "rotation": r_t.tolist(), "translation": t_t.tolist()},
            "diag": 2.0, "reference_point": [0.01, 0.02, -0.03],
            "symmetries": [{"rotation": np.eye(3).tolist(), "centre": [0, 0, 0]},
                           {"rotation": g.tolist(), "centre": c.tolist()}]}
    e = score((s_t, r_t, t_t), case, tol)
    assert e["success"] and e["symmetry"] == 0 and e["rotation_deg"] < 1e-5 \
        and e["translation_frac"] < 1e-12 and e["scale_frac"] < 1e-12, e
    # the symmetric pose: d = G (s R m + T - c) + c  =>  (s, G R, G T - G c + c)
    e = score((s_t, g @ r_t, g @ t_t - g @ c + c), case, tol)
    assert e["success"] and e["symmetry"] == 1 and e["rotation_deg"] < 1e-5 and e["translation_frac"] < 1e-12, e
    # 1 deg off passes, 3 deg off fails; 1 % translation passes; 2 % scale fails
    rz = lambda a: np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    e = score((s_t, rz(math.radians(1)) @ r_t, t_t), case, tol)
    assert abs(e["rotation_deg"] - 1) < 1e-6 and e["rotation_deg"] <= 2, e
    e = score((s_t, rz(math.radians(3)) @ r_t, t_t), case, tol)
    assert not e["success"] and abs(e["rotation_deg"] - 3) < 1e-6, e
    e = score((s_t * 1.02, r_t, t_t), case, tol)
    assert not e["success"] and abs(e["scale_frac"] - 0.02) < 1e-12, e
    e = score((s_t, r_t, t_t + np.array([0.02, 0, 0])), case, tol)
    assert e["success"] and abs(e["translation_frac"] - 0.01) < 1e-12, e
    # 4x4 splitting
    m = np.eye(4)
    m[:3, :3] = s_t * r_t
    m[:3, 3] = t_t
    s, r, t = similarity_from_matrix(m)
    assert abs(s - s_t) < 1e-12 and np.allclose(r, r_t) and np.allclose(t, t_t)
    print("scoring: ok")
    # the pre-scaling helpers: a pose found for k * m, composed, maps m the same way
    k, a = 1.7, s_t * r_t
    m4 = np.eye(4)
    m4[:3, :3], m4[:3, 3] = a, t_t
    pts = rng.normal(size=(5, 3))
    assert np.allclose(pts @ compose_prescale(m4, k)[:3, :3].T, (k * pts) @ a.T)
    assert known_scale({}) is None and known_scale({"known_scale": None}) is None \
        and known_scale({"known_scale": 2}) == 2.0
    assert prescale(3 * pts, pts, {}) == (prescale(3 * pts, pts, {})[0], False) \
        and abs(prescale(3 * pts, pts, {})[0] - 3) < 1e-12 and prescale(pts, pts, {"known_scale": 0.5}) == (0.5, True)
    print("pre-scaling helpers: ok")
    selftest_peers(rng, tol)
    # pycpd conversion on a synthetic case: model d = s R m + T of a scan m
    try:
        import pycpd  # noqa: F401
    except ImportError:
        print("pycpd: not installed, conversion not checked")
        return
    scan = rng.normal(size=(300, 3)) * np.array([1.0, 0.6, 0.3])
    # 25 deg, so that mixing up R and R^T (50 deg apart) would be caught
    r_t = random_rotation(rng, exact_deg=25.0)
    model = s_t * scan @ r_t.T + t_t
    case = {"truth": {"scale": s_t, "rotation": r_t.tolist(), "translation": t_t.tolist()},
            "diag": float(np.linalg.norm(model.max(0) - model.min(0))),
            "reference_point": scan.mean(0).tolist(), "seed": 3,
            "symmetries": [{"rotation": np.eye(3).tolist(), "centre": [0, 0, 0]}]}
    *est, _ = run_cpd(model, scan, case)
    e = score(est, case, tol)
    print(f"pycpd conversion: rotation {e['rotation_deg']:.2e} deg, translation {e['translation_frac']:.2e}, "
          f"scale {e['scale_frac']:.2e}")
    assert e["success"] and e["rotation_deg"] < 0.1, e
    print("pycpd conversion: ok")


def selftest_peers(rng, tol):
    """Each installed Open3D-based peer on a synthetic surface, once with the scale unknown and once known.

    The surface is make_sample.py's asymmetric one (FPFH needs a surface, not
    a blob); the scan is sampled independently of the model with 0.5 % noise,
    rotated by 25 deg (R and R^T are 50 deg apart), scale 0.8.
    """
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import make_sample
    model = make_sample.sample_surface(rng, 2000, make_sample.radius_asym)
    diag = float(np.linalg.norm(model.max(0) - model.min(0)))
    scan_d = make_sample.sample_surface(rng, 1000, make_sample.radius_asym)
    scan_d = scan_d + rng.normal(scale=0.005 * diag, size=scan_d.shape)
    s_t, r_t, t_t = 0.8, random_rotation(rng, exact_deg=25.0), np.array([0.1, -0.2, 0.15]) * diag
    scan = (scan_d - t_t) @ r_t / s_t
    base = {"truth": {"scale": s_t, "rotation": r_t.tolist(), "translation": t_t.tolist()},
            "diag": diag, "reference_point": scan.mean(0).tolist(), "seed": 5,
            "symmetries": [{"rotation": np.eye(3).tolist(), "centre": [0, 0, 0]}]}
    modules = {"open3d": ("open3d",), "teaser": ("open3d", "teaserpp_python"),
               "kiss-matcher": ("open3d", "kiss_matcher")}
    for method, mods in modules.items():
        try:
            for mod in mods:
                __import__(mod)
        except ImportError:
            print(f"{method}: not installed, not checked")
            continue
        prepare([method], 1)
        for ks in (None, s_t):
            *est, info = METHOD_FUNCS[method](model, scan, dict(base, known_scale=ks))
            e = score(est, base, tol)
            print(f"{method} ({'scale known' if ks else 'scale unknown'}): rotation {e['rotation_deg']:.2f} deg, "
                  f"translation {100 * e['translation_frac']:.2f} %, scale {100 * e['scale_frac']:.2f} %")
            assert e["success"], (method, ks, e, info)
            if ks is not None:
                assert e["scale_frac"] < 1e-9, e  # rigid after pre-scaling: the known scale comes back exactly
        print(f"{method}: ok")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir", nargs="?", help="export directory holding cases.json")
    ap.add_argument("--methods", default=",".join(ALL_METHODS),
                    help="comma-separated: open3d,cpd,teaser,kiss-matcher (and truth: the truth itself, "
                         "a scoring check); default open3d,cpd. teaser needs the Python 3.10 venv")
    ap.add_argument("--limit", type=int, help="run N cases spread evenly over the file")
    ap.add_argument("--first", action="store_true", help="with --limit: take the first N cases instead")
    ap.add_argument("--out", help="write per-case results and summaries as JSON here")
    ap.add_argument("--threads", type=int, default=1,
                    help="CPU threads for Open3D (TBB) and BLAS; default 1 (repeatable RANSAC, 0 = all)")
    ap.add_argument("--quiet", action="store_true", help="no per-case lines on stderr")
    ap.add_argument("--selftest", action="store_true",
                    help="check scoring, the pose conventions of the installed peers and the known-scale "
                         "paths, then exit")
    ap.add_argument("--merge", nargs="+", metavar="JSON",
                    help="merge --out files of runs on the same cases (e.g. one per venv), print the table; "
                         "--out writes the merged JSON")
    a = ap.parse_args(argv)
    if a.selftest:
        selftest()
        return 0
    if a.merge:
        report = merge(a.merge, a.out)
        methods = report["methods"]
    else:
        if not a.dir:
            ap.error("DIR is required")
        methods = [m.strip() for m in a.methods.split(",") if m.strip()]
        bad = [m for m in methods if m not in METHOD_FUNCS]
        if bad:
            ap.error(f"unknown method(s) {bad}; known: {list(METHOD_FUNCS)}")
        report = run(a.dir, methods, a.limit, a.first, a.out, verbose=not a.quiet, threads=a.threads)
    tol = report["tolerance"]
    print(f"suite {report['suite']} split {report['split']}: {len(report['cases'])} cases, tolerance "
          f"{tol['rotation_deg']} deg / {100 * tol['translation_frac']:g}% diag / {100 * tol['scale_frac']:g}% scale")
    sys.stderr.flush()
    print(format_table(report["summary"], methods))
    return 0


if __name__ == "__main__":
    sys.exit(main())
