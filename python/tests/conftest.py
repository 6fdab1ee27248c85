"""Fixtures of the svbtdf module's tests: one small simulated session, fitted once per test run
with the command line of the same build (SVBTDF_CLI, set by CTest), which the module's answers
are compared with."""

import json
import os
import subprocess

import pytest

CLI = os.environ.get("SVBTDF_CLI", "svbtdf")
SOURCE_DIR = os.environ.get("SVBTDF_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def svbtdf_cli(*args, check=True):
    """Runs the svbtdf program; returns its CompletedProcess (text)."""
    result = subprocess.run([CLI, "--quiet", *map(str, args)], capture_output=True, text=True)
    if check and result.returncode != 0:
        raise AssertionError(f"svbtdf {' '.join(map(str, args))} exited {result.returncode}:\n{result.stderr}")
    return result


class Tiny:
    """`svbtdf simulate --preset tiny` run through `svbtdf run --holdout 0.1`."""

    def __init__(self, root):
        self.root = root
        self.simulated = os.path.join(root, "simulated")  # the layout of scripts/demo.sh's out/demo
        self.session = os.path.join(self.simulated, "session")
        self.truth = os.path.join(self.simulated, "truth")
        self.material = os.path.join(root, "material")
        self.processed = os.path.join(root, "material.work", "processed")
        svbtdf_cli("simulate", "--preset", "tiny", "--out", self.simulated)
        svbtdf_cli("run", self.session, "--out", self.material, "--holdout", "0.1", "--representatives", "0.05")

    def cli_eval(self, col, row, wi, wo):
        out = svbtdf_cli("eval", self.material, "--texel", col, row, "--wi", *wi, "--wo", *wo, "--json").stdout
        return json.loads(out)


@pytest.fixture(scope="session")
def tiny(tmp_path_factory):
    return Tiny(str(tmp_path_factory.mktemp("tiny")))
