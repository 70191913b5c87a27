"""brdf-lab from Python: BRDFs, importance samplers and their validation over NumPy arrays.

Directions are in the local shading frame (z = normal): ``wo`` is the outgoing (view)
direction, ``wi`` the incident (light) one; pdfs of directions are per unit solid angle.
Every call is vectorised over rows of NumPy arrays, releases the GIL, runs in parallel and is
reproducible from a seed whatever the thread count. Bad input (a spec, a shape, NaN) raises
``ValueError`` with the library's message.

>>> import numpy as np, brdf_lab
>>> s = brdf_lab.DirectionSampler("adaptive", "ggx:alpha=0.2", seed=1)
>>> wi, pdf, f = s.sample(np.array([0.5, 0.0, 0.866]), np.random.default_rng(1).random((4, 2)))
>>> wi.shape, pdf.shape, f.shape
((4, 3), (4,), (4,))

The Mitsuba 3 plugin is in :mod:`brdf_lab.mitsuba` (``pip install "./python[mitsuba]"``).
"""

from __future__ import annotations

import json as _json
import os
from dataclasses import dataclass, field
from typing import Any, Iterable, Optional, Sequence, Union

from ._native import (
    PAR_CHUNK,
    Brdf,
    DirectionSampler,
    EnvMapSampler,
    PartitionSampler,
    models,
    num_threads,
    option_names,
    samplers,
    set_num_threads,
)
from . import _native

__all__ = [
    "Brdf",
    "DirectionSampler",
    "EnvMapSampler",
    "PartitionSampler",
    "ValidationResult",
    "StudyResult",
    "models",
    "samplers",
    "option_names",
    "validate",
    "study",
    "set_num_threads",
    "num_threads",
    "PAR_CHUNK",
]

__version__ = "0.1.0"

PathLike = Union[str, "os.PathLike[str]"]


@dataclass
class ValidationResult:
    """The validation suite's report (``brdf-lab validate --json``), parsed.

    ``passed`` is the run's verdict (every test at the Šidák-corrected level ``per_test_level``
    and every mutant caught); ``tests`` holds one dict per test (``brdf``, ``sampler``,
    ``theta_o``, ``test``, ``statistic``, ``p_value``, ``passed``, ``domain``, ``detail``);
    ``raw`` is the whole JSON document.
    """

    passed: bool
    alpha: float
    per_test_level: float
    tests: list = field(default_factory=list)
    mutants: list = field(default_factory=list)
    raw: dict = field(default_factory=dict)

    @property
    def failures(self) -> list:
        """The tests that failed."""
        return [t for t in self.tests if not t["passed"]]

    def __bool__(self) -> bool:
        return self.passed


@dataclass
class StudyResult:
    """A study's results (``results.json`` of ``brdf-lab study``), parsed: ``cells`` (one dict
    per sampler × mode × BRDF × θo × light cell), ``config``, ``notes`` and ``raw``."""

    cells: list
    config: dict
    notes: list
    raw: dict


def _items(x: Any) -> list:
    if x is None:
        return []
    if isinstance(x, (list, tuple)):
        return list(x)
    return [x]


def _names(x: Any, what: str) -> list:
    out = []
    for item in _items(x):
        if isinstance(item, Brdf) and item.is_callable:
            raise TypeError(
                f"{what}: a callable BRDF ({item.spec}) has no spec; validate() takes it, "
                "study() does not"
            )
        if isinstance(item, Brdf):
            out.append(item.spec)
        elif isinstance(item, str):
            out.append(item)
        else:
            raise TypeError(
                f"{what} must be registry names / specs (str) or brdf_lab.Brdf; "
                f"got {type(item).__name__}"
            )
    return out


def _brdfs(x: Any) -> tuple:
    """The specs and the callable BRDFs (:meth:`Brdf.from_callable`) of a selection."""
    items = _items(x)
    objects = [b for b in items if isinstance(b, Brdf) and b.is_callable]
    return _names([b for b in items if not any(b is o for o in objects)], "brdf"), objects


def _is_user_sampler(x: Any) -> bool:
    return callable(getattr(x, "sample", None)) and callable(getattr(x, "pdf", None))


def _user_name(obj: Any) -> str:
    name = getattr(obj, "name", None)
    return name if isinstance(name, str) and name else type(obj).__name__


def _user_pairs(d: dict) -> list:
    out = []
    for name, obj in d.items():
        if not _is_user_sampler(obj):
            raise TypeError(f"sampler {name!r} has no sample(wo, u) and pdf(wo, wi) methods")
        out.append((str(name), obj))
    return out


def _samplers(x: Any) -> tuple:
    """The selected names (registry names and Python samplers' names, in order) and the
    (name, object) pairs of the Python samplers: objects with ``sample(wo, u)`` and
    ``pdf(wo, wi)`` (named by their ``name`` attribute, else their class), alone, in a list,
    or by name in a dict."""
    if isinstance(x, dict):
        user = _user_pairs(x)
        return [n for n, _ in user], user
    items = [] if x is None else list(x) if isinstance(x, (list, tuple)) else [x]
    names, user = [], []
    for item in items:
        if isinstance(item, str):
            names.append(item)
        elif _is_user_sampler(item):
            user.append((_user_name(item), item))
            names.append(user[-1][0])
        else:
            raise TypeError(
                "samplers must be registry names (str) or objects with sample(wo, u) and "
                f"pdf(wo, wi); got {type(item).__name__}"
            )
    return names, user


def validate(
    sampler: Any = None,
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
) -> ValidationResult:
    """Run brdf-lab's validation suite (χ², KS, consistency, normalisation, unbiasedness) on
    samplers × BRDF specs × θo (degrees), like ``brdf-lab validate``.

    ``sampler``: a registry name, or any object with ``sample(wo, u) -> (wi, pdf)`` (or
    ``(wi, pdf, f)``) and ``pdf(wo, wi) -> pdf`` on NumPy batches (``wo`` (3,), ``u`` (N, 2)
    uniforms, ``wi`` (N, 3), pdfs per unit solid angle; named by its ``name`` attribute, else
    its class), or a list of these, or a dict ``{name: object}``. Python samplers run the same
    suite as the built-in ones, with draws batched into few calls; an exception they raise is
    raised here as ``ValueError``.

    ``brdf``: specs, :class:`Brdf` objects, or BRDFs written in Python
    (:meth:`Brdf.from_callable`, validated as objects and labelled ``python:NAME``; with
    only such BRDFs, only they run). An error of the callable is raised as ``ValueError``.

    ``None`` / empty selections take the tier's defaults (``quick=True``: the CI tier).
    ``json`` / ``report`` write the CLI's ``--json`` / ``--report`` files. Returns a
    :class:`ValidationResult`; raises ``ValueError`` for bad input (unknown sampler, bad
    spec, bad angle, too few samples). Failing samplers are reported, not raised.
    """
    names, user = _samplers(sampler)
    specs, objects = _brdfs(brdf)
    text = _native.validate_json(
        names,
        specs,
        [float(t) for t in (theta_o or [])],
        samples,
        seed,
        quick,
        mutants,
        alpha,
        None if json is None else os.fspath(json),
        None if report is None else os.fspath(report),
        [os.fspath(s) for s in sets],
        user,
        objects,
    )
    raw = _json.loads(text)
    return ValidationResult(
        passed=bool(raw["passed"]),
        alpha=raw["alpha"],
        per_test_level=raw.get("per_test_level", float("nan")),
        tests=raw.get("tests", []),
        mutants=raw.get("mutants", []),
        raw=raw,
    )


def study(
    samplers: Any = None,
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
    extra_samplers: Optional[dict] = None,
    variance_samples: Optional[int] = None,
    timing_samples: Optional[int] = None,
) -> StudyResult:
    """Run a variance-versus-cost study (``brdf-lab study``): samplers × BRDFs × θo × lights.

    ``preset="quick"`` is the CLI's ``--quick`` (``root``: the repository root, where
    ``../shared`` is looked for), ``"custom"`` the CLI's default grid; given arguments override
    it. ``out`` writes ``results.json``, ``results.csv``, ``report.md`` and ``plots/`` like the
    CLI (without the sphere images). ``shard="K/N"`` runs one shard.

    ``samplers`` may hold Python sampler objects (as for :func:`validate`), and
    ``extra_samplers={name: object}`` adds some to the preset's samplers: they are studied
    beside the built-in ones, their cost (one Python call per sample) measured as it is.
    """
    names, user = _samplers(samplers)
    user += _user_pairs(extra_samplers or {})
    text = _native.study_json(
        names,
        _names(brdfs, "brdfs"),
        [float(t) for t in (theta_o or [])],
        _names(lights, "lights"),
        preset,
        None if n_grid is None else [int(n) for n in n_grid],
        repetitions,
        seed,
        shard,
        None if out is None else os.fspath(out),
        None if root is None else os.fspath(root),
        user,
        variance_samples,
        timing_samples,
    )
    raw = _json.loads(text)
    return StudyResult(
        cells=raw.get("cells", []),
        config=raw.get("config", {}),
        notes=raw.get("notes", []),
        raw=raw,
    )
