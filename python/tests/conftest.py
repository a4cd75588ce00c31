"""Shared fixtures: the CLI binary the module is compared with, and .isw files it wrote."""
import json
import os
import subprocess

import pytest

import isowave  # noqa: F401  (fails early, with the import error, when PYTHONPATH misses the module)


@pytest.fixture(scope="session")
def cli():
    """Runs the isowave binary (ISOWAVE_CLI, set by ctest) and returns the completed process."""
    binary = os.environ.get("ISOWAVE_CLI")
    if not binary or not os.path.exists(binary):
        pytest.skip("ISOWAVE_CLI does not name the isowave binary (ctest sets it)")

    def run(*args, check=True):
        result = subprocess.run([binary, *map(str, args)], capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError(f"isowave {' '.join(map(str, args))} failed: {result.stderr}")
        return result

    return run


@pytest.fixture(scope="session")
def sphere_isw(cli, tmp_path_factory):
    """builtin:sphere:32 converted by the CLI (3 levels), with the CLI's --json result."""
    path = tmp_path_factory.mktemp("cli") / "sphere.isw"
    result = cli("convert", "builtin:sphere:32", "--levels", "3", "-o", path, "--json")
    return path, json.loads(result.stdout)["results"][0]


@pytest.fixture(scope="session")
def large_isw(cli, tmp_path_factory):
    """builtin:torus:96 at 4 levels converted by the CLI: a decode long enough, on a fast host too, to watch
    another thread run."""
    path = tmp_path_factory.mktemp("cli") / "torus.isw"
    cli("convert", "builtin:torus:96", "--levels", "4", "-o", path, "--quiet")
    return path
