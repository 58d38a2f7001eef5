import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture
def scenes():
    """The repository's scenes/ folder."""
    return REPO / "scenes"
