"""Type stubs of the native module (see groombake/__init__.py)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Literal, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike]
_Scope = Literal["vertex", "strand"]

__version__: str

class BadInput(Exception):
    """Bad input: an unreadable or malformed file, timeline or value (the CLI's exit code 2)."""

class BakeError(Exception):
    """A failure during the work: a bake or write that failed (the CLI's exit code 1)."""

class Groom:
    """Strands as flat arrays of points and per-strand vertex counts, attributes and frames."""

    @property
    def points(self) -> npt.NDArray[np.float32]:
        """Every point, strand after strand: shape (N, 3), in `units`, `up` axis."""
    @property
    def counts(self) -> npt.NDArray[np.int32]:
        """Vertices of each strand: shape (S,)."""
    @property
    def attributes(self) -> Dict[str, Tuple[npt.NDArray[Any], _Scope]]:
        """Name -> (values, scope): one row per vertex or per strand."""
    @property
    def frames(self) -> List[Tuple[float, npt.NDArray[np.float32]]]:
        """Time samples (seconds, points (N, 3)); empty for a static groom."""
    @property
    def units(self) -> str: ...
    @property
    def up(self) -> str: ...
    @property
    def strand_count(self) -> int: ...
    @property
    def vertex_count(self) -> int: ...
    @staticmethod
    def from_arrays(
        points: npt.ArrayLike,
        counts: npt.ArrayLike,
        *,
        frames: Optional[npt.ArrayLike] = None,
        times: Optional[List[float]] = None,
        units: str = "m",
        up: str = "y",
        **attributes: Union[npt.ArrayLike, Tuple[npt.ArrayLike, _Scope]],
    ) -> "Groom":
        """A groom from (N, 3) points, (S,) counts, optional (F, N, 3) frames and attributes."""
    def save(self, path: _Path, units: Optional[str] = None, up: Optional[str] = None) -> None:
        """Writes the groom; the extension picks the format."""

def load(path: _Path, units: Optional[str] = None, up: Optional[str] = None) -> Groom:
    """Reads a groom file of any supported format (BadInput when it cannot)."""

class Timeline:
    """A parsed and checked timeline."""

    @staticmethod
    def load(path: _Path) -> "Timeline": ...
    @staticmethod
    def from_dict(d: Dict[str, Any], base: Optional[_Path] = None) -> "Timeline":
        """A timeline from a dict with the TOML file's structure; BadInput names the key path."""
    def validate(self) -> Dict[str, Any]:
        """Reads the groom and colliders without simulating; returns counts."""
    @property
    def duration(self) -> float: ...
    @property
    def path(self) -> str: ...

class Report:
    """What a bake did: timeline, seed, threads, strands, vertices, stages, outputs, warnings..."""

    status: str
    started: str
    finished: str
    timeline: str
    sources: List[Dict[str, Any]]
    stages: List[Dict[str, Any]]
    outputs: List[Dict[str, Any]]
    warnings: List[str]
    def __getattr__(self, name: str) -> Any: ...
    def to_dict(self) -> Dict[str, Any]: ...

def bake(
    timeline: Union[Timeline, _Path],
    out: Optional[_Path] = None,
    threads: Optional[int] = None,
    seed: Optional[int] = None,
    progress: Optional[Union[Callable[[float, str], Any], Callable[[float], Any]]] = None,
) -> Report:
    """Runs a timeline and writes its exports; the GIL is released while it runs."""
