"""read_cloud and write_cloud: a round trip in every format, and bad files."""

import numpy as np
import pytest

import pficp


@pytest.fixture(scope="module")
def points():
    return np.random.default_rng(4).normal(size=(257, 3)) * [1.0, 1e-3, 1e3]


@pytest.mark.parametrize("ext", ["ply", "xyz", "csv"])
def test_round_trip_is_exact(tmp_path, points, ext):
    path = tmp_path / f"cloud.{ext}"
    pficp.write_cloud(path, points)
    back = pficp.read_cloud(path)
    assert back.dtype == np.float64 and back.shape == points.shape
    assert np.array_equal(back, points)


def test_pcd_round_trip_is_float32(tmp_path, points):
    path = tmp_path / "cloud.pcd"
    pficp.write_cloud(str(path), points)
    back = pficp.read_cloud(str(path))
    assert np.array_equal(back, points.astype(np.float32).astype(np.float64))


def test_the_cli_reads_what_python_writes(cli, tmp_path, points):
    path = tmp_path / "cloud.ply"
    pficp.write_cloud(path, points.astype(np.float32))
    out = tmp_path / "again.xyz"
    # `pficp gen` cannot read; registering the cloud to itself with --out-aligned writes it back.
    cli("register", "--model", path, "--scan", path, "--method", "icp", "--iterations", 1, "--out-aligned", out)
    assert pficp.read_cloud(out).shape == points.shape


def test_a_missing_file_is_an_os_error(tmp_path):
    with pytest.raises(OSError) as e:
        pficp.read_cloud(tmp_path / "missing.ply")
    assert "missing.ply" in str(e.value)


def test_an_unknown_extension_is_a_value_error(tmp_path, points):
    with pytest.raises(ValueError) as e:
        pficp.write_cloud(tmp_path / "cloud.obj", points)
    assert ".obj" in str(e.value) or "obj" in str(e.value)


def test_a_malformed_file_is_a_value_error(tmp_path):
    path = tmp_path / "bad.xyz"
    path.write_text("1 2 3\n4 5\n")
    with pytest.raises(ValueError) as e:
        pficp.read_cloud(path)
    assert "bad.xyz" in str(e.value) and "\n" not in str(e.value)


def test_writing_to_a_missing_folder_is_an_os_error(tmp_path, points):
    with pytest.raises(OSError):
        pficp.write_cloud(tmp_path / "no" / "such" / "cloud.ply", points)
