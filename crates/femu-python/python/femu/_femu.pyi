"""Type stubs of femu's native module (checked by mypy in CI)."""

from os import PathLike
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt
import scipy.sparse

_Path = Union[str, "PathLike[str]"]
_F64 = npt.NDArray[np.float64]

class FemuError(Exception):
    """A malformed file, an invalid model or a numerical failure, in femu's words."""

class Model:
    """A finite element model read from a file, checked and assembled once."""

    @property
    def path(self) -> str: ...
    @property
    def free_count(self) -> int: ...
    @property
    def K(self) -> scipy.sparse.csc_matrix: ...
    @property
    def M(self) -> scipy.sparse.csc_matrix: ...
    @property
    def dofs(self) -> npt.NDArray[np.int64]: ...
    @property
    def node_ids(self) -> npt.NDArray[np.uint64]: ...
    @property
    def coords(self) -> _F64: ...
    @property
    def lumped(self) -> bool: ...
    @property
    def total_mass(self) -> float: ...
    @property
    def warnings(self) -> List[str]: ...
    def modes(
        self,
        count: Optional[int] = None,
        *,
        shift_hz: Optional[float] = None,
        band_hz: Optional[Tuple[float, float]] = None,
        block_size: Optional[int] = None,
        progress: Optional[Callable[[int], Any]] = None,
        damped: bool = False,
    ) -> Modes: ...
    def write_modes_uff(self, modes: Modes, path: _Path, *, damped: bool = False) -> None: ...

class Modes:
    """Eigenvalues, M-normalised shapes, residuals and the Sturm proof."""

    @property
    def values(self) -> _F64: ...
    @property
    def frequencies_hz(self) -> _F64: ...
    @property
    def vectors(self) -> _F64: ...
    @property
    def residuals(self) -> _F64: ...
    @property
    def residual_kinds(self) -> List[str]: ...
    @property
    def sturm(self) -> Dict[str, Any]: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def __len__(self) -> int: ...

class Test:
    """Test modes on sensors of a model."""

    @staticmethod
    def from_arrays(
        model: Model,
        nodes: Sequence[int],
        directions: _F64,
        frequencies_hz: Sequence[float],
        shapes: _F64,
        *,
        damping: Optional[Sequence[float]] = None,
        shapes_imaginary: Optional[_F64] = None,
    ) -> Test: ...
    @property
    def frequencies_hz(self) -> _F64: ...
    @property
    def shapes(self) -> _F64: ...
    @property
    def shapes_imaginary(self) -> Optional[_F64]: ...
    @property
    def nodes(self) -> List[int]: ...
    @property
    def directions(self) -> _F64: ...
    @property
    def C(self) -> scipy.sparse.csr_matrix: ...
    def __len__(self) -> int: ...

class Results:
    """Another solver's modes with its nodes (CalculiX .frd, Nastran .f06): the model side of a correlation."""

    @property
    def warnings(self) -> List[str]: ...
    @property
    def frequencies_hz(self) -> List[float]: ...
    @property
    def node_ids(self) -> List[int]: ...
    @property
    def shapes(self) -> _F64: ...
    def __len__(self) -> int: ...

def read_results(path: _Path, *, nodes: Optional[_Path] = None) -> Results: ...
def read_model(
    path: _Path,
    *,
    lumped: bool = False,
    lenient: bool = False,
    young: Optional[float] = None,
    poisson: Optional[float] = None,
    density: Optional[float] = None,
    fix: Optional[Sequence[str]] = None,
    bricks: str = "full",
    nodes: Optional[_Path] = None,
    shells: Optional[Mapping[str, float]] = None,
    beams: Optional[Mapping[str, str]] = None,
    structural_damping: Optional[float] = None,
) -> Model: ...
def read_test(
    path: _Path, model: Union[Model, Results], *, test_units: Optional[float] = None
) -> Test: ...
def mac(a: _F64, b: Optional[_F64] = None) -> _F64: ...
def expand(model: Model, test: Test, *, method: str = "dynamic") -> _F64: ...
def estimate(
    model: Model,
    test: Test,
    *,
    expansion: str = "dynamic",
    count: Optional[int] = None,
    mac_threshold: float = 0.8,
    max_frequency_error: Optional[float] = None,
    damped: bool = False,
) -> Dict[str, Any]: ...
def run_demo(
    out: _Path, *, quick: bool = False, progress: Optional[Callable[[str], Any]] = None
) -> Dict[str, Any]: ...
def correlate(
    model: Union[Model, Results],
    test: Test,
    *,
    count: Optional[int] = None,
    mac_threshold: float = 0.8,
    max_frequency_error: Optional[float] = None,
    damped: bool = False,
) -> Dict[str, Any]: ...
def frf(
    model: Model,
    path: _Path,
    *,
    damping_ratio: Optional[float] = None,
    loss_factor: Optional[float] = None,
    rayleigh: Optional[Sequence[float]] = None,
    direct: bool = False,
    damping_from: Optional[_Path] = None,
    modes_up_to: float = 2.0,
    update: Optional[Sequence[str]] = None,
    tuned_lines: Optional[int] = None,
    update_lines: int = 24,
    update_all: bool = False,
    sb_ebe_only: bool = False,
    min_coherence: Optional[float] = None,
    loss_factor_per_set: bool = False,
) -> Dict[str, Any]: ...
def removal_study(model: Model, test: Test, *, expansion: str = "dynamic") -> Dict[str, Any]: ...
def update(
    model: Model,
    test: Test,
    sets: Sequence[str],
    *,
    tuned: Optional[int] = None,
    method: str = "ies",
    select: str = "forward",
    shapes: bool = True,
    frequency_uncertainty: Optional[float] = None,
    shape_uncertainty: Optional[float] = None,
    test_error: Optional[float] = None,
    discretisation: bool = True,
    progress: Optional[Callable[[Dict[str, Any]], Any]] = None,
) -> Dict[str, Any]: ...
