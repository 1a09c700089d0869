"""Shared fixtures of the Python package's tests: the repository's examples and the `swarf`
command (for comparing the package with it)."""

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"
CASES = sorted((EXAMPLES / "cases").glob("*.json"))


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: takes more than a few seconds")


@pytest.fixture(scope="session")
def swarf_bin():
    """The `swarf` command: $SWARF_BIN, else the workspace's build (debug, then release), else
    PATH. Missing: skipped, unless SWARF_REQUIRE_CLI=1."""
    cands = [os.environ.get("SWARF_BIN"), ROOT / "target/debug/swarf", ROOT / "target/release/swarf", shutil.which("swarf")]
    for c in cands:
        if c and pathlib.Path(c).is_file():
            return str(c)
    if os.environ.get("SWARF_REQUIRE_CLI") == "1":
        pytest.fail("SWARF_REQUIRE_CLI=1 but no swarf command (cargo build -p swarf-cli)")
    pytest.skip("no swarf command to compare with (cargo build -p swarf-cli, or set SWARF_BIN)")
