# pytest fixtures of the Python package's tests (tests/python), run by CTest (tests/CMakeLists.txt:
# python.pytest) with the package importable from the build tree (PYTHONPATH=build/<preset>/python).
# CTest gives the paths in the environment: GYROCHAR_ANALYZE (the program), GYROCHAR_TEST_DATA
# (tests/data) and GYROCHAR_ALLANTOOLS (the allantools peer beside the checkout, ../shared/peers).
import os
import pathlib

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]


def _env_path(name, default):
    return pathlib.Path(os.environ.get(name, default))


@pytest.fixture(scope="session")
def data_dir():
    return _env_path("GYROCHAR_TEST_DATA", SOURCE_DIR / "tests" / "data")


@pytest.fixture(scope="session")
def analyze_program():
    path = os.environ.get("GYROCHAR_ANALYZE")
    if not path or not os.access(path, os.X_OK):
        pytest.skip("GYROCHAR_ANALYZE does not name the gyrochar-analyze program (CTest sets it)")
    return path


def load(path):
    """The values of a reference file ('#' comments)."""
    return np.loadtxt(path, comments="#", ndmin=1)
