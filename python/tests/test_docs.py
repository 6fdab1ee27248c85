"""docs/python.md's example runs, and the type stubs describe the module as it is."""

import ast
import os
import re
import subprocess
import sys

import svbtdf
from conftest import SOURCE_DIR

STUBS = os.path.join(os.path.dirname(svbtdf.__file__), "__init__.pyi")


def python_blocks(path):
    with open(path) as f:
        return re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)


def test_the_notebook_example_of_docs_python_md_runs(tiny):
    example = python_blocks(os.path.join(SOURCE_DIR, "docs", "python.md"))[0]
    result = subprocess.run([sys.executable, "-c", example], capture_output=True, text=True,
                            env={**os.environ, "SVBTDF_DEMO": tiny.root})
    assert result.returncode == 0, result.stderr
    integral = float(re.search(r"integral of D h.z: ([0-9.]+)", result.stdout).group(1))
    assert abs(integral - 1.0) < 0.02, result.stdout
    assert "held-out relative RMSE" in result.stdout and "texel (5, 7): relative RMSE" in result.stdout


def stub_names(tree):
    """Top-level names of the stubs and, per class, its members."""
    names, members = set(), {}
    for node in tree.body:
        if isinstance(node, ast.ClassDef):
            names.add(node.name)
            members[node.name] = {n.name if isinstance(n, ast.FunctionDef) else n.target.id
                                  for n in node.body if isinstance(n, (ast.FunctionDef, ast.AnnAssign))}
        elif isinstance(node, ast.FunctionDef):
            names.add(node.name)
    return names, members


def test_the_stubs_name_everything_the_module_exports_and_nothing_else():
    with open(STUBS) as f:
        names, members = stub_names(ast.parse(f.read()))
    assert names == set(svbtdf.__all__)
    for cls in ("Material", "Session", "SliceStore"):
        public = {n for n in dir(getattr(svbtdf, cls)) if not n.startswith("_")}
        assert members[cls] - {"__contains__"} == public, cls
    for name in svbtdf.__all__:
        assert getattr(svbtdf, name).__doc__, name  # help() explains each
