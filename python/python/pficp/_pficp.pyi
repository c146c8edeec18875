"""Type stubs of the PF-ICP extension module (pficp._pficp)."""

import os
from typing import Any, Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Points = npt.NDArray[Union[np.float32, np.float64]]
"""An N x 3 C-contiguous array of float32 or float64."""

Verdict = Literal["confident", "ambiguous", "unreliable"]
State = Literal["acquiring", "tracking", "lost", "reacquired"]
Method = Literal["pf-icp", "icp", "welsch", "cauchy", "sparse-icp", "em-icp"]

class BoardError(OSError):
    """The board or its serial port failed (missing, silent, echoing, a corrupted or refused frame, a timeout)."""

class Registration:
    """One registration's result: the pose (scan to model, d = s R m + T) and PF-ICP's verdict on it."""

    @property
    def transformation(self) -> npt.NDArray[np.float64]:
        """The 4 x 4 matrix [[s R, T], [0, 1]], as Open3D's RegistrationResult.transformation."""
    @property
    def scale(self) -> float: ...
    @property
    def rotation(self) -> npt.NDArray[np.float64]:
        """3 x 3."""
    @property
    def translation(self) -> npt.NDArray[np.float64]:
        """(3,)."""
    @property
    def covariance(self) -> Optional[npt.NDArray[np.float64]]:
        """7 x 7 in covariance_order (model units, scale, rad); NaN where undetermined; None for a baseline."""
    @property
    def covariance_order(self) -> List[str]: ...
    @property
    def sigma(self) -> Optional[npt.NDArray[np.float64]]:
        """(7,) one-sigma values in covariance_order; NaN where undetermined; None for a baseline."""
    @property
    def fitness(self) -> Optional[float]: ...
    @property
    def inlier_rmse(self) -> Optional[float]: ...
    @property
    def verdict(self) -> Optional[Verdict]: ...
    @property
    def reasons(self) -> List[str]: ...
    @property
    def alternatives(self) -> List[Dict[str, Any]]:
        """Other poses that fit as well, then (beside some of those) poses that fit worse but are not ruled out: transformation, scale, rotation, translation, cost, excess_sigmas, fits_as_well."""
    @property
    def msd(self) -> float: ...
    @property
    def iterations(self) -> int: ...
    @property
    def seconds(self) -> float: ...
    @property
    def engine(self) -> Literal["software", "board", "board-host-driven"]: ...
    def to_dict(self) -> Dict[str, Any]:
        """The keys of `pficp register --json` (without the file names and the command line)."""

class TrackFrame:
    """One tracked frame: the track's state, the frame's pose and verdict."""

    @property
    def frame(self) -> int: ...
    @property
    def state(self) -> State: ...
    @property
    def verdict(self) -> Verdict: ...
    @property
    def reasons(self) -> List[str]: ...
    @property
    def transformation(self) -> npt.NDArray[np.float64]: ...
    @property
    def scale(self) -> float: ...
    @property
    def rotation(self) -> npt.NDArray[np.float64]: ...
    @property
    def translation(self) -> npt.NDArray[np.float64]: ...
    @property
    def covariance(self) -> npt.NDArray[np.float64]: ...
    @property
    def sigma(self) -> npt.NDArray[np.float64]: ...
    @property
    def fitness(self) -> float: ...
    @property
    def inlier_rmse(self) -> float: ...
    @property
    def alternatives(self) -> List[Dict[str, Any]]: ...
    @property
    def global_registration(self) -> bool: ...
    @property
    def seconds(self) -> float: ...
    def to_dict(self) -> Dict[str, Any]:
        """The keys of one line of `pficp track --json`."""

class Board:
    """A PF-ICP board on a serial port; opening it identifies it (BoardError if it does not answer)."""

    def __init__(self, port: str, *, baud: Optional[int] = None, timeout_ms: Optional[int] = None) -> None: ...
    @property
    def port(self) -> str: ...
    def identify(self) -> Dict[str, int]: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Board": ...
    def __exit__(self, *args: Any) -> None: ...

class Tracker:
    """A tracker of one model over consecutive scans (`pficp track`); update(scan) a frame."""

    def __init__(
        self,
        model: Points,
        *,
        fps: Optional[float] = None,
        scale: Optional[float] = None,
        scale_range: Optional[Sequence[float]] = None,
        viewpoint: Optional[Sequence[float]] = None,
        seed: Optional[int] = None,
        board: Optional[Board] = None,
    ) -> None: ...
    def update(self, scan: Points) -> TrackFrame: ...
    @property
    def frames(self) -> int: ...
    @property
    def fixed_scale(self) -> Optional[float]: ...
    def close(self) -> None: ...
    def __enter__(self) -> "Tracker": ...
    def __exit__(self, *args: Any) -> None: ...

def register(
    model: Points,
    scan: Points,
    *,
    method: Method = "pf-icp",
    scale: Optional[float] = None,
    scale_range: Optional[Sequence[float]] = None,
    viewpoint: Optional[Sequence[float]] = None,
    seed: Optional[int] = None,
    clusters: Optional[int] = None,
    particles: Optional[int] = None,
    iterations: Optional[int] = None,
    init: Literal["auto", "index", "nearest"] = "auto",
    board: Optional[Board] = None,
    board_points: Optional[int] = None,
    host_driven: bool = False,
    rescue: bool = True,
) -> Registration:
    """Register scan to model; None takes the CLI's default (seed 1, 100 clusters, 50 particles, 50 iterations)."""

def read_cloud(path: Union[str, os.PathLike[str]]) -> npt.NDArray[np.float64]:
    """Read a PLY, PCD, XYZ or CSV cloud as an N x 3 float64 array."""

def write_cloud(path: Union[str, os.PathLike[str]], points: Points) -> None:
    """Write an N x 3 array as a PLY, PCD, XYZ or CSV cloud (by the extension)."""
