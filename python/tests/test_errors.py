"""Bad input: a Python exception with one clear line, never a crash."""

import os

import numpy as np
import pytest

import pficp


@pytest.fixture(scope="module")
def good():
    rng = np.random.default_rng(2)
    return rng.normal(size=(500, 3))


def one_line(e):
    message = str(e.value)
    assert message and "\n" not in message, message
    return message


BAD_ARRAYS = [
    ("a list", lambda g: g.tolist(), ["NumPy array", "list"]),
    ("a scalar", lambda g: 3.0, ["NumPy array"]),
    ("two columns", lambda g: g[:, :2].copy(), ["shape (N, 3)", "(500, 2)"]),
    ("a transpose", lambda g: g.T, ["shape (N, 3)", "(3, 500)"]),
    ("three dimensions", lambda g: g.reshape(500, 3, 1), ["shape (N, 3)"]),
    ("empty", lambda g: np.zeros((0, 3)), ["empty"]),
    ("not contiguous", lambda g: np.asfortranarray(g), ["C-contiguous", "np.ascontiguousarray"]),
    ("a strided slice", lambda g: g[::2], ["C-contiguous"]),
    ("integers", lambda g: g.astype(np.int64), ["int64", "float32 or float64"]),
    ("complex", lambda g: g.astype(np.complex128), ["complex128"]),
    ("objects", lambda g: g.astype(object), ["object", "float32 or float64"]),
    ("a NaN", lambda g: np.where(np.arange(500)[:, None] == 7, np.nan, g), ["non-finite", "point 7"]),
    ("an infinity", lambda g: np.where(np.arange(500)[:, None] == 9, np.inf, g), ["non-finite", "point 9"]),
    ("a huge coordinate", lambda g: np.where(np.arange(500)[:, None] == 3, 1e200, g), ["point 3", "limit"]),
]


@pytest.mark.parametrize("what,make,words", BAD_ARRAYS, ids=[b[0] for b in BAD_ARRAYS])
@pytest.mark.parametrize("which", ["model", "scan"])
def test_a_bad_array_is_a_value_error(good, what, make, words, which):
    arrays = {"model": good, "scan": good}
    arrays[which] = make(good)
    with pytest.raises(ValueError) as e:
        pficp.register(arrays["model"], arrays["scan"])
    message = one_line(e)
    assert message.startswith(which), message
    for w in words:
        assert w in message, message


BAD_OPTIONS = [
    (dict(particles=0), ["--particles", "at least 1"]),
    (dict(iterations=10**9), ["--iterations", "at most"]),
    (dict(clusters=0), ["--clusters"]),
    (dict(scale=-1.0), ["--scale", "positive"]),
    (dict(scale=float("nan")), ["--scale"]),
    (dict(scale_range=(2.0, 1.0)), ["--scale-range", "LO <= HI"]),
    (dict(scale_range=(1.0,)), ["--scale-range", "two numbers"]),
    (dict(scale=1.0, scale_range=(0.5, 2.0)), ["--scale", "--scale-range"]),
    (dict(viewpoint=(1.0, 2.0)), ["--viewpoint", "three numbers"]),
    (dict(viewpoint=(0.0, float("inf"), 0.0)), ["--viewpoint", "finite"]),
    (dict(method="ransac"), ["unknown method", "pf-icp"]),
    (dict(init="random"), ["unknown init"]),
    (dict(host_driven=True), ["board"]),
    (dict(board_points=50), ["board"]),
    (dict(method="sparse-icp", scale=1.0), ["--scale", "sparse-icp"]),
    (dict(clusters=600), ["clusters"]),
]


@pytest.mark.parametrize("kwargs,words", BAD_OPTIONS, ids=[str(o[0]) for o in BAD_OPTIONS])
def test_an_absurd_option_is_a_value_error(good, kwargs, words):
    with pytest.raises(ValueError) as e:
        pficp.register(good, good, **kwargs)
    message = one_line(e)
    for w in words:
        assert w in message, message


def test_a_cloud_beyond_the_point_limit_is_refused_before_it_is_copied(good):
    # A broadcast view: 20 million rows of 3 floats that take no memory of their own.
    huge = np.broadcast_to(good[:1], (20_000_000, 3))
    with pytest.raises(ValueError) as e:
        pficp.register(huge, good)
    assert "20000000 points, more than the limit" in one_line(e)


def test_wrong_types_are_type_errors(good):
    with pytest.raises(TypeError):
        pficp.register(good, good, seed="one")
    with pytest.raises((TypeError, OverflowError)):
        pficp.register(good, good, seed=-1)
    with pytest.raises(TypeError):
        pficp.register(good)


def test_units_far_apart_are_refused(good):
    with pytest.raises(ValueError) as e:
        pficp.register(good, good * 1e-9)
    assert "different units" in one_line(e)


def test_a_missing_board_is_a_board_error():
    with pytest.raises(pficp.BoardError) as e:
        pficp.Board("/nonexistent/ttyUSB7")
    assert isinstance(e.value, OSError)
    assert "/nonexistent/ttyUSB7" in one_line(e)


def test_a_silent_board_is_a_board_error_not_a_hang():
    # A real pseudo-terminal nobody answers on.
    master, slave = os.openpty()
    try:
        with pytest.raises(pficp.BoardError) as e:
            pficp.Board(os.ttyname(slave), baud=3_000_000, timeout_ms=200)
        assert "did not answer" in one_line(e) or "no reply" in one_line(e)
    finally:
        os.close(master)
        os.close(slave)


def test_absurd_link_options_are_value_errors():
    with pytest.raises(ValueError) as e:
        pficp.Board("/dev/null", baud=1)
    assert "--baud 1" in one_line(e)
    with pytest.raises(ValueError) as e:
        pficp.Board("/dev/null", timeout_ms=0)
    assert "--timeout-ms" in one_line(e)
