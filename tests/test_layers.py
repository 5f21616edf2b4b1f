"""Layer contracts (pyproject.toml, import-linter): kept by the code, and able to fail.

The second group copies the package, adds one forbidden import and checks that the
contract named for it breaks: a contract that cannot fail would prove nothing.
"""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT), "--no-cache"], cwd=cwd, capture_output=True, text=True,
                          env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin"})


def test_the_package_keeps_every_contract():
    result = _lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "4 kept, 0 broken" in result.stdout


@pytest.mark.parametrize(("module", "line", "broken"), [
    ("simulation/leak.py", "import torch", "torch is imported only by the learning layer"),
    ("learning/data/leak.py", "import torch", "torch is imported only by the learning layer"),
    ("learning/leak.py", "import casadi", "CasADi is imported only by the fitting layer"),
    ("fitting/leak.py", "import matplotlib.pyplot",
     "matplotlib is imported only by posture_id.plotting"),
    ("bodies/leak.py", "def f():\n    from posture_id.simulation import simulate\n",
     "Stages are layered"),
    ("fitting/leak.py", "from posture_id.learning import __doc__", "Stages are layered"),
])
def test_a_forbidden_import_breaks_its_contract(tmp_path, module, line, broken):
    shutil.copytree(ROOT / "posture_id", tmp_path / "posture_id",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    (tmp_path / "posture_id" / module).write_text(line + "\n")
    result = _lint(tmp_path)
    assert result.returncode != 0
    verdicts = [ln for ln in result.stdout.splitlines() if ln.startswith(broken)]
    assert verdicts and verdicts[0].endswith("BROKEN"), result.stdout
    assert "1 broken" in result.stdout, result.stdout  # only the contract named for it


#: Prints each import cycle among the package's modules (TYPE_CHECKING and function-level
#: imports counted), one per line.
_CYCLES = """
import grimp
graph = grimp.build_graph("posture_id", include_external_packages=False)
modules = graph.modules
edges = {m: set(graph.find_modules_directly_imported_by(m)) & modules for m in modules}
index, low, stack, on, found = {}, {}, [], set(), []
def visit(v):
    index[v] = low[v] = len(index); stack.append(v); on.add(v)
    for w in edges[v]:
        if w not in index:
            visit(w); low[v] = min(low[v], low[w])
        elif w in on:
            low[v] = min(low[v], index[w])
    if low[v] == index[v]:
        part = []
        while True:
            w = stack.pop(); on.discard(w); part.append(w)
            if w == v:
                break
        if len(part) > 1:
            found.append(" ".join(sorted(part)))
import sys
sys.setrecursionlimit(100000)
for m in sorted(modules):
    if m not in index:
        visit(m)
print("\\n".join(found))
"""


def _cycles(cwd: Path) -> list[str]:
    result = subprocess.run([sys.executable, "-c", _CYCLES], cwd=cwd, capture_output=True,
                            text=True, env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    return [line for line in result.stdout.splitlines() if line]


def test_no_module_imports_itself_through_others():
    assert _cycles(ROOT) == []


def test_an_import_cycle_is_found_even_for_type_hints(tmp_path):
    shutil.copytree(ROOT / "posture_id", tmp_path / "posture_id",
                    ignore=shutil.ignore_patterns("__pycache__"))
    options = tmp_path / "posture_id" / "fitting" / "options.py"
    options.write_text(options.read_text() + "\nfrom typing import TYPE_CHECKING\n\nif "
                       "TYPE_CHECKING:\n    from posture_id.fitting.least_squares import "
                       "FitRun\n")
    cycles = _cycles(tmp_path)
    assert len(cycles) == 1 and "posture_id.fitting.options" in cycles[0], cycles


def test_no_file_of_the_package_is_ignored_by_git():
    """A tracked package file that .gitignore matches (a pattern meant for the root's
    data/ matched posture_id/learning/data/) is skipped by ruff's walk and hides a new
    module there from ``git status``."""
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    ignored = subprocess.run(["git", "ls-files", "--cached", "--ignored", "--exclude-standard",
                              "posture_id", "tests", "benchmarks", "docs"], cwd=ROOT,
                             capture_output=True, text=True, check=True).stdout.split()
    assert ignored == []


def _benchmark_imports(folder: Path) -> list[str]:
    """``file: line`` of every line under ``folder`` that puts benchmarks/ on the import
    path or imports one of its scripts."""
    scripts = {p.stem for p in (ROOT / "benchmarks").glob("*.py")}
    pattern = re.compile(r"^\s*(?:from|import)\s+(\w+)|sys\.path\.\w+\(.*benchmarks")
    found = []
    for path in sorted(folder.rglob("*.py")):
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            match = pattern.search(line)
            if match and (match.group(1) is None or match.group(1) in scripts):
                found.append(f"{path.relative_to(folder.parent)}:{number}")
    return found


def test_no_test_or_package_module_imports_a_benchmark(tmp_path):
    """Benchmarks measure; they are not part of the build: the tests and the package
    import nothing from benchmarks/ (a test's cases live in tests/)."""
    assert _benchmark_imports(ROOT / "tests") == []
    assert _benchmark_imports(ROOT / "posture_id") == []
    planted = tmp_path / "tests"
    planted.mkdir()
    folder = "bench" + "marks"  # spelled apart so that this file holds no such line
    (planted / "test_x.py").write_text(f'import sys\nsys.path.insert(0, "{folder}")\n'
                                       "from same_results import main\n")
    assert _benchmark_imports(planted) == ["tests/test_x.py:2", "tests/test_x.py:3"]
