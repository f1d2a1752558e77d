import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def data():
    """The repository's real test data (tests/data); a missing file fails the test that reads it."""
    return REPO / "tests" / "data"


@pytest.fixture(scope="session")
def kelvin_bin():
    """The `kelvin` program the Python renders are compared with (KELVIN_BIN, or target/debug/kelvin)."""
    path = pathlib.Path(os.environ.get("KELVIN_BIN", REPO / "target" / "debug" / "kelvin"))
    assert path.exists(), f"{path}: build it first (cargo build), or set KELVIN_BIN"
    return path
