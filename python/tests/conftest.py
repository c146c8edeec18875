"""Shared fixtures: the `pficp` CLI (to compare with and to generate data), its generated
model-1 case, a moving sequence of it, and a box whose symmetry the verdict must report."""

import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import pficp

REPO = Path(__file__).resolve().parents[2]


def _binary(env_name, name):
    """A workspace binary: `$env_name`, else the newest built one under target/."""
    given = os.environ.get(env_name)
    if given:
        return given
    found = [p for p in (REPO / "target" / d / name for d in ("debug", "release")) if p.exists()]
    if not found:
        pytest.fail(f"{name} is not built: set {env_name} or run cargo build")
    return str(max(found, key=lambda p: p.stat().st_mtime))


@pytest.fixture(scope="session")
def cli():
    """Run `pficp ARGS...`; return the completed process (text)."""
    binary = _binary("PFICP_BIN", "pficp")

    def run(*args, check=True, input=None):
        out = subprocess.run([binary, *map(str, args)], capture_output=True, text=True, input=input)
        if check and out.returncode != 0:
            raise AssertionError(f"pficp {' '.join(map(str, args))} failed: {out.stderr}")
        return out

    return run


@pytest.fixture(scope="session")
def sim_board_binary():
    return _binary("PFICP_SIM_BOARD", "pficp-sim-board")


@pytest.fixture(scope="session")
def model1(cli, tmp_path_factory):
    """`pficp gen` model-1: 2,000 model points, an independently sampled scan of 1,000 points
    with 0.2% noise under a random pose and scale; (model path, scan path, truth dict)."""
    d = tmp_path_factory.mktemp("model1")
    cli("gen", "--model", "model-1", "--out-dir", d, "--points", 2000, "--scan-points", 1000,
        "--sampling", "independent", "--noise", 0.002, "--random-transform", "--seed", 3)
    truth = json.loads((d / "model-1-truth.json").read_text())
    return d / "model-1.ply", d / "model-1-scan.ply", truth


def run_child(code, timeout):
    """Run `code` in a child Python; fail if it fails or is still running after `timeout` s
    (a deadlock fails the test instead of hanging the suite)."""
    import sys

    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"still running after {timeout} s: stuck")
    assert out.returncode == 0, out.stderr


def box_surface(n, sides, rng):
    """`n` points uniformly on the surface of a box with these side lengths (exactly D2
    symmetric when the sides differ)."""
    a, b, c = sides
    areas = np.array([b * c, b * c, a * c, a * c, a * b, a * b])
    face = rng.choice(6, size=n, p=areas / areas.sum())
    u, v = rng.uniform(-0.5, 0.5, (2, n))
    half = np.array(sides) / 2
    p = np.empty((n, 3))
    for f in range(6):
        m = face == f
        axis, sign = f // 2, 1 if f % 2 == 0 else -1
        others = [k for k in range(3) if k != axis]
        p[m, axis] = sign * half[axis]
        p[m, others[0]] = u[m] * sides[others[0]]
        p[m, others[1]] = v[m] * sides[others[1]]
    return p


def pose_error(transformation, truth, diagonal):
    """(rotation error in degrees, translation error as a share of the diagonal, relative
    scale error) of a 4 x 4 against a truth dict (scale, rotation, translation)."""
    s = np.cbrt(np.linalg.det(transformation[:3, :3]))
    r = transformation[:3, :3] / s
    rt = np.array(truth["rotation"])
    cos = (np.trace(r.T @ rt) - 1) / 2
    angle = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    dt = np.linalg.norm(transformation[:3, 3] - np.array(truth["translation"])) / diagonal
    return angle, dt, abs(s / truth["scale"] - 1)


def diagonal(points):
    return float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))


FRAMES = 12


def rotation_z(deg):
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])


@pytest.fixture(scope="module")
def sequence(model1):
    """model-1 turning at 15 deg/s and drifting, seen at 30 frames a second: each frame is
    1,000 of the model's points with noise of 0.05% of the diagonal, moved so that the
    truth (scan to model) is the frame's pose; (model, frames, truths)."""
    model = pficp.read_cloud(model1[0])
    rng = np.random.default_rng(11)
    diag = diagonal(model)
    frames, truths = [], []
    tilt = np.array([[1, 0, 0], [0, np.cos(0.4), -np.sin(0.4)], [0, np.sin(0.4), np.cos(0.4)]])
    for k in range(FRAMES):
        r = rotation_z(20 + 0.5 * k) @ tilt
        t = np.array([0.3, -0.2, 0.1]) * diag + np.array([0.002, 0.001, 0.0]) * diag * k
        s = 0.8
        pts = model[rng.choice(len(model), 1000, replace=False)]
        pts = pts + rng.normal(scale=0.0005 * diag, size=pts.shape)
        scan = (pts - t) @ r / s  # m = R^T (d - T) / s, row-wise
        frames.append(np.ascontiguousarray(scan))
        truths.append({"scale": s, "rotation": r.tolist(), "translation": t.tolist()})
    return model, frames, truths
