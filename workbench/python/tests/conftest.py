"""Shared fixtures: the `flarebench` binary the module is compared with, and a runner.

The binary is `$FLAREBENCH_BIN`, else `debug/flarebench` in `$CARGO_TARGET_DIR` or the
workspace's `target/` (what `cargo build --workspace` makes; the `python` stage of .ci/run
runs after it). A missing binary fails the tests that need it: it is never skipped.
"""

import json
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def _binary():
    if os.environ.get("FLAREBENCH_BIN"):
        return Path(os.environ["FLAREBENCH_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "debug" / "flarebench"


@pytest.fixture(scope="session")
def cli():
    """Runs `flarebench ARGS…` quietly and returns its standard output."""
    binary = _binary()
    if not binary.is_file():
        pytest.fail(f"no flarebench binary at {binary}: run `cargo build --workspace` first")

    def run(*args):
        done = subprocess.run(
            [str(binary), "--quiet", *map(str, args)],
            capture_output=True,
            text=True,
            check=False,
        )
        assert done.returncode == 0, f"flarebench {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout

    return run


@pytest.fixture(scope="session")
def cli_info(cli):
    """`flarebench info LENS --json`, parsed."""
    return lambda lens: json.loads(cli("info", lens, "--json"))
