"""pficp.Tracker: a moving part tracked frame after frame, the same frames as `pficp track`."""

import json

import numpy as np
import pytest

import pficp
from conftest import FRAMES, diagonal, pose_error, run_child


def test_tracks_a_moving_part(sequence):
    model, frames, truths = sequence
    diag = diagonal(model)
    with pficp.Tracker(model, fps=30) as tracker:
        states = []
        for scan, truth in zip(frames, truths):
            f = tracker.update(scan)
            states.append(f.state)
            angle, dt, ds = pose_error(f.transformation, truth, diag)
            assert angle < 1.0 and dt < 0.01 and ds < 0.01, (f, angle, dt, ds)
            assert f.verdict == "confident", (f, f.reasons)
        assert tracker.frames == FRAMES
    assert states[0] == "acquiring" and set(states[1:]) == {"tracking"}, states
    # After ten tracked frames the scale is settled and held.
    assert tracker.fixed_scale is None  # closed: nothing held any more


def test_the_same_frames_as_pficp_track(cli, sequence, tmp_path):
    model, frames, _ = sequence
    pficp.write_cloud(tmp_path / "model.ply", model)
    scans = tmp_path / "scans"
    scans.mkdir()
    for k, scan in enumerate(frames[:6]):
        pficp.write_cloud(scans / f"frame-{k:03}.ply", scan)
    out = cli("track", "--model", tmp_path / "model.ply", "--scans", scans, "--json", "--seed", 4).stdout
    lines = [json.loads(line) for line in out.splitlines()]
    tracker = pficp.Tracker(model, seed=4)
    for scan, line in zip(frames[:6], lines):
        d = tracker.update(scan).to_dict()
        for key in ["frame", "state", "verdict", "matrix", "covariance", "sigma", "fitness", "alternatives", "global"]:
            assert d[key] == line[key], key
    assert len(lines) == 6


def test_a_frame_of_something_else_loses_the_track(sequence):
    model, frames, _ = sequence
    tracker = pficp.Tracker(model)
    for scan in frames[:4]:
        tracker.update(scan)
    noise = np.random.default_rng(1).uniform(-1, 1, size=(1000, 3)) * diagonal(model)
    f = tracker.update(noise)
    assert f.state == "lost" and f.verdict == "unreliable", f
    f = tracker.update(frames[5])
    assert f.state == "reacquired", f


def test_bad_frames_and_options_are_value_errors(sequence):
    model, frames, _ = sequence
    tracker = pficp.Tracker(model)
    with pytest.raises(ValueError, match="at least 10 points"):
        tracker.update(frames[0][:5])
    with pytest.raises(ValueError, match="non-finite"):
        tracker.update(np.full((100, 3), np.nan))
    with pytest.raises(ValueError, match="--fps"):
        pficp.Tracker(model, fps=0)
    with pytest.raises(ValueError, match="--scale"):
        pficp.Tracker(model, scale=-2)
    tracker.close()
    with pytest.raises(ValueError, match="closed"):
        tracker.update(frames[0])



def test_threads_sharing_a_tracker_take_turns(sequence, tmp_path):
    # Each call waits for the other without the GIL, so neither holds up the other's return
    # (a thread waiting with the GIL would wait for ever for one that needs it to return).
    # In a child process, so that a stuck pair fails the test instead of hanging it.
    model, frames, _ = sequence
    np.save(tmp_path / "model.npy", model)
    np.save(tmp_path / "frames.npy", np.stack(frames))
    run_child(f"""
import threading, numpy as np, pficp
model = np.load({str(tmp_path / "model.npy")!r})
frames = list(np.load({str(tmp_path / "frames.npy")!r}))
tracker = pficp.Tracker(model)
done = []
def work(scans):
    for scan in scans:
        done.append(tracker.update(np.ascontiguousarray(scan)).frame)
        assert tracker.frames >= 1
threads = [threading.Thread(target=work, args=(frames[k::2],)) for k in range(2)]
for t in threads: t.start()
for t in threads: t.join()
assert sorted(done) == list(range(len(frames))), done
""", timeout=120)
