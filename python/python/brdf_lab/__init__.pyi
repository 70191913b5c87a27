"""Type stubs of brdf_lab (the NumPy API of brdf-lab)."""

import os
from dataclasses import dataclass
from typing import Any, Dict, Iterable, Optional, Protocol, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]
PathLike = Union[str, os.PathLike[str]]

__version__: str
PAR_CHUNK: int

class Brdf:
    """A BRDF from a spec string (``"ggx:alpha=0.2"``, ``"rgl:PATH"``, ``"merl:PATH"``, …)."""

    def __init__(self, spec: str) -> None: ...
    @property
    def spec(self) -> str: ...
    @property
    def name(self) -> str: ...
    @property
    def is_isotropic(self) -> bool: ...
    def eval(self, wo: ArrayLike, wi: ArrayLike) -> F64:
        """Luminance of f_r(wo, wi), shape (N,); wo, wi (3,) or (N, 3)."""
    def eval_rgb(self, wo: ArrayLike, wi: ArrayLike) -> F64:
        """Linear RGB f_r(wo, wi), shape (N, 3)."""

class DirectionSampler:
    """A registry direction sampler built for a BRDF; pdfs per unit solid angle."""

    def __init__(self, name: str, brdf: Union[Brdf, str], seed: int = 1, **options: Any) -> None: ...
    def sample(
        self, wo: ArrayLike, u: Union[ArrayLike, int], seed: Optional[int] = None, rgb: bool = False
    ) -> Tuple[F64, F64, F64]:
        """(wi (N, 3), pdf (N,), f (N,) luminance or (N, 3) with rgb=True)."""
    def pdf(self, wo: ArrayLike, wi: ArrayLike) -> F64: ...
    @property
    def name(self) -> str: ...
    @property
    def brdf(self) -> Brdf: ...
    @property
    def seed(self) -> int: ...
    @property
    def bytes_used(self) -> int: ...
    @property
    def build_seconds(self) -> float: ...
    @property
    def build_report(self) -> Optional[str]: ...
    @property
    def bound_violations(self) -> Optional[int]: ...
    @property
    def can_save(self) -> bool: ...
    def save(self, path: PathLike) -> None: ...
    @staticmethod
    def load(path: PathLike, brdf: Union[Brdf, str, None] = None, seed: int = 1) -> "DirectionSampler": ...

class EnvMapSampler:
    """Directions ∝ luminance per solid angle of a lat-long map (file, "sky", or array)."""

    def __init__(
        self,
        name: str,
        path_or_array: Union[PathLike, ArrayLike],
        seed: int = 1,
        n_max: Optional[float] = None,
        max_depth: Optional[int] = None,
        leaf_choice: Optional[str] = None,
    ) -> None: ...
    def sample(self, u: Union[ArrayLike, int], seed: Optional[int] = None) -> Tuple[F64, F64, F64, F64]:
        """(uv (N, 2), pdf_uv (N,), dirs (N, 3), pdf_sa (N,))."""
    def pdf(self, dirs: ArrayLike) -> F64: ...
    def pdf_uv(self, uv: ArrayLike) -> F64: ...
    def invert(self, uv: ArrayLike) -> F64: ...
    @property
    def name(self) -> str: ...
    @property
    def bytes_used(self) -> int: ...
    @property
    def build_report(self) -> dict: ...

class PartitionSampler:
    """The adaptive partition sampler (or grid CDFs) of a 2D density table."""

    def __init__(
        self,
        density: ArrayLike,
        domain: Tuple[float, float, float, float] = (0.0, 0.0, 1.0, 1.0),
        method: str = "adaptive",
        seed: int = 1,
        n_max: Optional[float] = None,
        max_depth: Optional[int] = None,
        leaf_choice: Optional[str] = None,
    ) -> None: ...
    def sample(self, u: Union[ArrayLike, int], seed: Optional[int] = None) -> Tuple[F64, F64]: ...
    def pdf(self, points: ArrayLike) -> F64: ...
    def invert(self, points: ArrayLike) -> F64: ...
    @property
    def method(self) -> str: ...
    @property
    def bytes_used(self) -> int: ...
    @property
    def build_report(self) -> dict: ...

@dataclass
class ValidationResult:
    passed: bool
    alpha: float
    per_test_level: float
    tests: list
    mutants: list
    raw: dict
    @property
    def failures(self) -> list: ...
    def __bool__(self) -> bool: ...

@dataclass
class StudyResult:
    cells: list
    config: dict
    notes: list
    raw: dict

def models() -> list: ...
def samplers() -> list: ...
def option_names() -> dict: ...
def set_num_threads(n: Optional[int] = None) -> None: ...
def num_threads() -> int: ...
class UserSampler(Protocol):
    """A sampler written in Python (see :func:`validate`)."""

    def sample(self, wo: np.ndarray, u: np.ndarray) -> tuple: ...
    def pdf(self, wo: np.ndarray, wi: np.ndarray) -> np.ndarray: ...

def validate(
    sampler: Union[str, UserSampler, Sequence[Union[str, UserSampler]], Dict[str, UserSampler], None] = None,
    brdf: Union[str, Brdf, Sequence[Union[str, Brdf]], None] = None,
    theta_o: Optional[Iterable[float]] = None,
    samples: Optional[int] = None,
    seed: int = 1,
    *,
    quick: bool = True,
    mutants: bool = False,
    alpha: float = 0.01,
    json: Optional[PathLike] = None,
    report: Optional[PathLike] = None,
    sets: Sequence[PathLike] = (),
) -> ValidationResult: ...
def study(
    samplers: Union[str, UserSampler, Sequence[Union[str, UserSampler]], Dict[str, UserSampler], None] = None,
    brdfs: Union[str, Brdf, Sequence[Union[str, Brdf]], None] = None,
    theta_o: Optional[Iterable[float]] = None,
    lights: Union[str, Sequence[str], None] = None,
    *,
    preset: str = "quick",
    n_grid: Optional[Sequence[int]] = None,
    repetitions: Optional[int] = None,
    seed: int = 1,
    shard: Optional[str] = None,
    out: Optional[PathLike] = None,
    root: Optional[PathLike] = None,
    extra_samplers: Optional[Dict[str, UserSampler]] = None,
    variance_samples: Optional[int] = None,
    timing_samples: Optional[int] = None,
) -> StudyResult: ...
