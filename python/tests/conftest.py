"""Shared fixtures: the ../shared data directory (tests that need it skip with the reason)."""

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("BRDF_LAB_SHARED", REPO / ".." / "shared")).resolve()


def shared_file(rel: str) -> Path:
    p = SHARED / rel
    if not p.is_file():
        pytest.skip(f"{p} not found (the ../shared data directory beside the repository is absent)")
    return p


def direction(theta_deg: float, phi_deg: float = 0.0) -> np.ndarray:
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    return np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
