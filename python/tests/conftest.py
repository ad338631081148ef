"""Shared paths of the pytest suite: the repository (for its committed
reference figures and example runs) and `../shared` (present in CI and on
the developers' machines, absent on a user's clone: tests that need it
skip with a message)."""

import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"


def meijaard2007():
    """Table 1 and 2 of Meijaard et al. (2007), as committed for the Rust
    tests (runtime/tests/data/meijaard2007.toml, with its source)."""
    import tomllib

    with open(REPO / "runtime/tests/data/meijaard2007.toml", "rb") as f:
        return tomllib.load(f)


@pytest.fixture
def shared():
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent (a clone without ../shared)")
    return SHARED
