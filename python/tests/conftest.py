"""Fixtures shared by the tests of the Python package: the repository, the
command-line binary (built if missing, so the suite runs on a clean clone)
and the paper's grid as a file."""

import json
import os
import subprocess
from pathlib import Path

import pytest

REPOSITORY = Path(__file__).resolve().parents[2]
FORMULA = "!unsafe U goal"


def run_cli(cli, *arguments, check=True):
    """Runs the CLI; returns the completed process (stdout and stderr as text)."""
    process = subprocess.run(
        [str(cli), *map(str, arguments)], capture_output=True, text=True, check=False
    )
    if check and process.returncode != 0:
        raise AssertionError(f"posg-fsc {arguments} failed: {process.stderr}")
    return process


@pytest.fixture(scope="session")
def cli():
    """The `posg-fsc` binary: $POSG_FSC_CLI, else target/release/posg-fsc,
    built with cargo when it is not there."""
    given = os.environ.get("POSG_FSC_CLI")
    if given:
        return Path(given)
    binary = REPOSITORY / "target" / "release" / "posg-fsc"
    if not binary.exists():
        subprocess.run(
            ["cargo", "build", "--release", "--locked", "--bin", "posg-fsc"],
            cwd=REPOSITORY,
            check=True,
        )
    return binary


@pytest.fixture(scope="session")
def grid_file(cli, tmp_path_factory):
    """The paper's 3x2 grid written by `posg-fsc example grid`."""
    path = tmp_path_factory.mktemp("grid") / "grid.posg.json"
    run_cli(cli, "example", "grid", "--out", path)
    return path


def cli_json(cli, *arguments):
    """The CLI's JSON report on stdout."""
    return json.loads(run_cli(cli, *arguments).stdout)


def cli_error(cli, *arguments):
    """The CLI's error message (stderr without `error: `); it must fail."""
    process = run_cli(cli, *arguments, check=False)
    assert process.returncode != 0, f"posg-fsc {arguments} succeeded"
    message = process.stderr.strip().splitlines()[-1]
    assert message.startswith("error: "), process.stderr
    return message[len("error: ") :]
