"""PF-ICP: point-cloud registration with a verdict on every pose.

ICP, k-means clustering and a particle filter over scale, rotation and translation
(the paper's PF-ICP), with a global search for low-overlap camera views and an honest
verdict: ``confident`` (act on the pose), ``ambiguous`` (alternatives fit as well) or
``unreliable`` (do not act on it). NumPy arrays in and out; Open3D clouds through
``np.asarray(pcd.points)``.

>>> import numpy as np, pficp
>>> model = pficp.read_cloud("model.ply")
>>> scan = pficp.read_cloud("scan.ply")
>>> result = pficp.register(model, scan, scale=1.0, viewpoint=(0, 0, 0))
>>> result.verdict, result.transformation

- ``register(model, scan, ...)``: one registration (as ``pficp register``).
- ``Tracker(model, ...)``: ``update(scan)`` a frame (as ``pficp track``).
- ``Board(port)``: the FPGA board on a serial port, for both.
- ``read_cloud(path)``, ``write_cloud(path, points)``: PLY, PCD, XYZ, CSV.
"""

from ._pficp import (
    Board,
    BoardError,
    Registration,
    Tracker,
    TrackFrame,
    __version__,
    read_cloud,
    register,
    write_cloud,
)

__all__ = [
    "Board",
    "BoardError",
    "Registration",
    "Tracker",
    "TrackFrame",
    "__version__",
    "read_cloud",
    "register",
    "write_cloud",
]
