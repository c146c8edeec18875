"""pficp.Board against the Verilated board (`pficp-sim-board --check`, the RTL as hdl-gen
generates it, every byte it sends compared with the reference) over a real pseudo-terminal."""

import json
import subprocess

import numpy as np
import pytest

import pficp
from conftest import diagonal, pose_error, run_child

SETTINGS = dict(particles=16, iterations=4, clusters=20, board_points=100, seed=3)
FLAGS = ["--particles", 16, "--iterations", 4, "--clusters", 20, "--board-points", 100, "--seed", 3]


@pytest.fixture(scope="module")
def sim_board(sim_board_binary):
    """The board's device path; on teardown the board's own check must have passed."""
    p = subprocess.Popen([sim_board_binary, "--check"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    path = p.stdout.readline().strip()
    assert path.startswith("/dev/"), path
    yield path
    p.terminate()
    _, err = p.communicate(timeout=60)
    assert p.returncode == 0 and "all equal" in err, err


@pytest.fixture(scope="module")
def small(model1):
    """model-1's model (every 4th point) and 300 points of its scan."""
    model = np.ascontiguousarray(pficp.read_cloud(model1[0])[::4])
    scan = np.ascontiguousarray(pficp.read_cloud(model1[1])[::3][:300])
    return model, scan


def test_the_board_identifies_itself(sim_board):
    with pficp.Board(sim_board) as board:
        who = board.identify()
        assert who["version"] >= 6 and who["lanes"] == 8 and who["clock_hz"] == 50_000_000
        assert board.port == sim_board
    with pytest.raises(ValueError, match="closed"):
        board.identify()


def test_the_filter_on_the_board_gives_the_cli_s_pose(cli, sim_board, small, tmp_path):
    model, scan = small
    pficp.write_cloud(tmp_path / "model.ply", model)
    pficp.write_cloud(tmp_path / "scan.ply", scan)
    with pficp.Board(sim_board) as board:
        r = pficp.register(model, scan, board=board, **SETTINGS)
    assert r.engine == "board"
    d = r.to_dict()
    assert d["port"] == sim_board and d["settings"]["board_points"] == 100
    out = cli("register", "--model", tmp_path / "model.ply", "--scan", tmp_path / "scan.ply", "--board", sim_board,
              "--json", *FLAGS)
    line = json.loads(out.stdout)
    assert line["engine"] == "board"
    assert np.array_equal(r.transformation, np.array(line["matrix"]))
    assert d["verdict"] == line["verdict"] and d["covariance"] == line["covariance"]


def test_a_second_thread_waits_for_the_board(sim_board, small, tmp_path):
    # A registration holds the link; identify from another thread waits for it, without
    # the GIL, and then answers (with the GIL it would wait for ever). In a child process,
    # so that a stuck pair fails the test instead of hanging it.
    model, scan = small
    np.save(tmp_path / "model.npy", model)
    np.save(tmp_path / "scan.npy", scan)
    run_child(f"""
import threading, numpy as np, pficp
model, scan = np.load({str(tmp_path / "model.npy")!r}), np.load({str(tmp_path / "scan.npy")!r})
with pficp.Board({sim_board!r}) as board:
    result, who = [], []
    started = threading.Event()
    def register():
        started.set()
        result.append(pficp.register(model, scan, board=board, **{SETTINGS!r}))
    t = threading.Thread(target=register)
    t.start()
    started.wait()
    u = threading.Thread(target=lambda: who.append(board.identify()))
    u.start()
    t.join()
    u.join()
    assert result and result[0].engine == "board"
    assert who and who[0]["version"] >= 6
""", timeout=300)


def test_a_tracker_holds_the_board_until_it_is_closed(sim_board, sequence):
    model, frames, truths = sequence
    diag = diagonal(model)
    board = pficp.Board(sim_board)
    tracker = pficp.Tracker(model, board=board)
    with pytest.raises(ValueError, match="held by a Tracker"):
        board.identify()
    states = []
    for scan, truth in zip(frames[:3], truths):
        f = tracker.update(scan)
        states.append(f.state)
        angle, dt, ds = pose_error(f.transformation, truth, diag)
        assert angle < 1.0 and dt < 0.01 and ds < 0.01, (f, angle, dt, ds)
        assert f.to_dict()["engine"] == "board"
    assert states == ["acquiring", "tracking", "tracking"], states
    tracker.close()
    # The board holds the model the tracker put on it.
    assert board.identify()["model_count"] == len(model)
    board.close()
