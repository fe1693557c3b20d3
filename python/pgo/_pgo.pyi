"""Type stubs of the extension module pgo._pgo (python/src/lib.rs). Use it through ``pgo``:
``pgo.Graph``, ``pgo.Graph3``, ``pgo.read``, ``pgo.solve``, ``pgo.certify``, ``pgo.spectrum``."""

import os
from typing import List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

VERSION: str

ArrayLike = npt.ArrayLike
PathLike = Union[str, "os.PathLike[str]"]

class PgoError(ValueError):
    """An error of pgo's library: a request it cannot carry out."""

class ParseError(PgoError):
    """An input error at a place; ``str(e)`` is ``PATH:LINE:COL: error: REASON``."""

    path: str
    line: int
    column: int
    reason: str

class Graph:
    """A planar pose graph (see ``pgo.Graph.__doc__``)."""

    def __init__(
        self,
        poses: ArrayLike,
        edges: ArrayLike,
        measurements: ArrayLike,
        information: Optional[ArrayLike] = None,
        ids: Optional[ArrayLike] = None,
        fixed: Optional[ArrayLike] = None,
        *,
        allow_indefinite: bool = False,
    ) -> None: ...
    @property
    def poses(self) -> npt.NDArray[np.float64]:
        """(n, 3) x, y, theta per pose, ascending id order."""
    @property
    def ids(self) -> npt.NDArray[np.int64]:
        """(n,) vertex ids, ascending."""
    @property
    def edges(self) -> npt.NDArray[np.int64]:
        """(m, 2) vertex ids (i, j), file order."""
    @property
    def edge_indices(self) -> npt.NDArray[np.int64]:
        """(m, 2) row indices into ``poses``."""
    @property
    def measurements(self) -> npt.NDArray[np.float64]:
        """(m, 3) dx, dy, dtheta."""
    @property
    def information(self) -> npt.NDArray[np.float64]:
        """(m, 6) information upper triangles, g2o order."""
    @property
    def fixed(self) -> npt.NDArray[np.int64]:
        """(k,) ids of the FIX poses."""
    @property
    def landmark_ids(self) -> npt.NDArray[np.int64]:
        """(L,) landmark ids."""
    @property
    def landmarks(self) -> npt.NDArray[np.float64]:
        """(L, 2) landmark positions."""
    @property
    def observations(self) -> npt.NDArray[np.int64]:
        """(o, 2) pose id, landmark id."""
    @property
    def observation_measurements(self) -> npt.NDArray[np.float64]:
        """(o, 2) dx, dy in the pose's frame."""
    @property
    def observation_information(self) -> npt.NDArray[np.float64]:
        """(o, 3) I11 I12 I22."""
    @property
    def dimension(self) -> int:
        """2."""
    @property
    def num_poses(self) -> int: ...
    @property
    def num_edges(self) -> int: ...
    @property
    def format(self) -> str:
        """"g2o" or "toro"."""
    @property
    def dialect(self) -> str:
        """"g2o", "toro-info", "toro-cov" or "g2o-cov"."""
    @property
    def has_vertices(self) -> bool: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def source(self) -> str: ...
    def with_poses(self, poses: ArrayLike, landmarks: Optional[ArrayLike] = None) -> Graph: ...
    def write(
        self, path: PathLike, format: Optional[str] = None, dialect: Optional[str] = None
    ) -> None: ...
    def to_text(self, format: Optional[str] = None, dialect: Optional[str] = None) -> str: ...
    def __eq__(self, other: object) -> bool: ...

class Graph3:
    """A 3D pose graph (see ``pgo.Graph3.__doc__``); ``pgo.read`` returns one for a 3D file."""

    def __init__(
        self,
        poses: ArrayLike,
        edges: ArrayLike,
        measurements: ArrayLike,
        information: Optional[ArrayLike] = None,
        ids: Optional[ArrayLike] = None,
        fixed: Optional[ArrayLike] = None,
        *,
        form: str = "g2o",
        allow_indefinite: bool = False,
    ) -> None: ...

    @property
    def poses(self) -> npt.NDArray[np.float64]:
        """(n, 7) x y z qx qy qz qw (g2o) or (n, 6) x y z roll pitch yaw (TORO), as read."""
    @property
    def ids(self) -> npt.NDArray[np.int64]:
        """(n,) vertex ids, ascending."""
    @property
    def edges(self) -> npt.NDArray[np.int64]:
        """(m, 2) vertex ids (i, j), file order."""
    @property
    def edge_indices(self) -> npt.NDArray[np.int64]:
        """(m, 2) row indices into ``poses``."""
    @property
    def measurements(self) -> npt.NDArray[np.float64]:
        """(m, 7) or (m, 6), as ``poses``."""
    @property
    def information(self) -> npt.NDArray[np.float64]:
        """(m, 21) information upper triangles, row by row, as in the file."""
    @property
    def fixed(self) -> npt.NDArray[np.int64]:
        """(k,) ids of the FIX poses."""
    @property
    def dimension(self) -> int:
        """3."""
    @property
    def num_poses(self) -> int: ...
    @property
    def num_edges(self) -> int: ...
    @property
    def format(self) -> str:
        """"g2o" (quaternions) or "toro" (Euler angles)."""
    @property
    def dialect(self) -> str:
        """"g2o" or "toro-info"."""
    @property
    def warnings(self) -> List[str]: ...
    @property
    def source(self) -> str: ...
    def with_poses(self, poses: ArrayLike) -> Graph3: ...
    def write(
        self, path: PathLike, format: Optional[str] = None, dialect: Optional[str] = None
    ) -> None: ...
    def to_text(self, format: Optional[str] = None, dialect: Optional[str] = None) -> str: ...
    def __eq__(self, other: object) -> bool: ...

def read_path(
    path: PathLike,
    format: Optional[str] = None,
    dialect: Optional[str] = None,
    strict: bool = False,
    ignore_equiv: bool = False,
    allow_indefinite: bool = False,
) -> Union[Graph, Graph3]: ...
def read_bytes(
    data: bytes,
    name: str = "<string>",
    format: Optional[str] = None,
    dialect: Optional[str] = None,
    strict: bool = False,
    ignore_equiv: bool = False,
    allow_indefinite: bool = False,
) -> Union[Graph, Graph3]: ...
def solve(
    graph: Union[Graph, Graph3],
    weights: str = "isotropic",
    tol: float = 1e-6,
    method: str = "auto",
    solver: Optional[str] = None,
    max_rank: int = 6,
    staircase_budget: float = 50.0,
    refine: bool = False,
) -> Tuple[str, npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...
def certify(
    graph: Union[Graph, Graph3],
    poses: Optional[ArrayLike] = None,
    landmarks: Optional[ArrayLike] = None,
    weights: str = "isotropic",
    tol: float = 1e-6,
) -> str: ...
def spectrum(
    graph: Union[Graph, Graph3], k: int = 0, weights: str = "isotropic", solver: str = "ipm"
) -> Tuple[str, List[int]]: ...
