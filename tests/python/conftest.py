"""Shared fixtures: the neurarm binary (built by scripts/test before pytest runs) and one quick
paper run for the tests of its closed loops."""
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def neurarm() -> pathlib.Path:
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = target / "release" / "neurarm"
    if not binary.exists():
        subprocess.run(["cargo", "build", "--release", "--locked"], cwd=ROOT, check=True)
    return binary


@pytest.fixture(scope="session")
def paper(neurarm, tmp_path_factory) -> pathlib.Path:
    """`neurarm paper --quick --fmi3`'s output folder: systems/*.toml, *.ssp, fmu/ (and the FMI
    3.0 twins in fmu/fmi3/), data/."""
    out = tmp_path_factory.mktemp("paper")
    subprocess.run([neurarm, "paper", "--quick", "--fmi3", "-o", out], check=True, capture_output=True)
    return out
