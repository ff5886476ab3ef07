"""The notebooks: one per paper, committed cleared, importing only public names, and running clean."""

from __future__ import annotations

import ast
import copy
import importlib
import json
import sys
from pathlib import Path

import nbformat
import pytest

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
PAPERS = ("enferadi2017", "harada2011", "harada2015", "zhao2011")
PUBLIC_MODULES = {
    "plm_pin",
    "plm_pin.workspace",
    "plm_pin.dynamics",
    "plm_pin.families",
    "plm_pin.families.prrrp",
    "plm_pin.kinematics",
    "plm_pin.models",
    "plm_pin.statics",
    "plm_pin.viz",
}
"""The packages a notebook may import from, and only names in their ``__all__``."""

CELL_TIMEOUT = 300
"""Longest a cell may run [s]: a hang fails, a slow machine does not."""


def _notebook(name: str) -> nbformat.NotebookNode:
    return nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)


def _code(nb: nbformat.NotebookNode) -> list[str]:
    return [cell.source for cell in nb.cells if cell.cell_type == "code"]


def test_there_is_one_notebook_per_paper():
    """notebooks/ holds exactly the four papers' notebooks."""
    assert sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")) == sorted(PAPERS)


KERNELSPEC = {"display_name": "Python 3", "language": "python", "name": "python3"}


def cleared(nb: nbformat.NotebookNode) -> nbformat.NotebookNode:
    """``nb`` as it is committed: no outputs, execution counts or cell metadata; only the kernel named."""
    nb = copy.deepcopy(nb)
    for cell in nb.cells:
        cell.metadata = nbformat.NotebookNode()
        if cell.cell_type == "code":
            cell.outputs = []
            cell.execution_count = None
    nb.metadata = nbformat.from_dict({"kernelspec": KERNELSPEC, "language_info": {"name": "python"}})
    return nb


@pytest.mark.parametrize("name", PAPERS)
def test_notebook_is_committed_cleared(name):
    """No outputs, no execution counts, no cell metadata; notebook metadata only names the kernel."""
    nb = _notebook(name)
    nbformat.validate(nb)
    assert nb == cleared(nb), f"notebooks/{name}.ipynb has outputs or metadata: run make clear-notebooks"


def test_clearing_removes_outputs_counts_and_metadata():
    """cleared() empties what a Jupyter session adds, and keeps the sources."""
    nb = _notebook("harada2011")
    dirty = copy.deepcopy(nb)
    code = next(c for c in dirty.cells if c.cell_type == "code")
    code.outputs = [nbformat.v4.new_output("stream", name="stdout", text="1\n")]
    code.execution_count = 3
    code.metadata["scrolled"] = True
    dirty.metadata["language_info"]["version"] = "3.11.2"
    assert dirty != nb
    assert cleared(dirty) == nb


def _private_uses(source: str) -> list[str]:
    """Every import of plm_pin that is not public, and every ``_name`` attribute, in one code cell."""
    bad = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and (node.module or "").split(".")[0] == "plm_pin":
            module = node.module or ""
            if module not in PUBLIC_MODULES:
                bad.append(f"from {module} import ...: not one of {sorted(PUBLIC_MODULES)}")
                continue
            exported = set(importlib.import_module(module).__all__)
            bad += [f"{module}.{a.name} is not in its __all__" for a in node.names if a.name not in exported]
        elif isinstance(node, ast.Import):
            bad += [
                f"import {a.name}"
                for a in node.names
                if a.name.split(".")[0] == "plm_pin" and a.name not in PUBLIC_MODULES
            ]
        elif isinstance(node, ast.Attribute):
            if node.attr.startswith("_") and not node.attr.startswith("__"):
                bad.append(f"attribute {node.attr}")
                continue
            module = _dotted(node.value)
            if module in PUBLIC_MODULES and f"{module}.{node.attr}" not in PUBLIC_MODULES:
                if node.attr not in importlib.import_module(module).__all__:
                    bad.append(f"{module}.{node.attr} is not in its __all__")
    return bad


def _dotted(node: ast.expr) -> str | None:
    """``a.b.c`` for a chain of attributes on a name, else None."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        head = _dotted(node.value)
        return None if head is None else f"{head}.{node.attr}"
    return None


@pytest.mark.parametrize("name", PAPERS)
def test_notebook_uses_only_the_public_api(name):
    """Imports from plm_pin name public packages and names in their __all__; no _private attributes."""
    bad = [use for source in _code(_notebook(name)) for use in _private_uses(source)]
    assert not bad, f"{name}: {bad}"


def test_the_public_api_check_catches_private_uses():
    """The checker flags private modules, names outside __all__ and private attributes, and only those."""
    source = (
        "from plm_pin.statics.reactions import body_name\n"
        "from plm_pin.kinematics import _private\n"
        "import plm_pin._arguments\n"
        "mech._cache\n"
        "plm_pin.loading\n"
        "plm_pin.kinematics.mode_graph.Mode\n"
        "from plm_pin.kinematics import classify\n"
        "plm_pin.viz.fig8, plm_pin.load, mech.__class__\n"
    )
    found = _private_uses(source)
    assert [use.split(":")[0] for use in found] == [
        "from plm_pin.statics.reactions import ...",
        "plm_pin.kinematics._private is not in its __all__",
        "import plm_pin._arguments",
        "attribute _cache",
        "plm_pin.loading is not in its __all__",
        "plm_pin.kinematics.mode_graph is not in its __all__",
    ]


@pytest.fixture(scope="module")
def kernel_specs(tmp_path_factory):
    """A kernel spec that starts this interpreter (the venv's), whatever other Jupyter specs exist."""
    from jupyter_client.kernelspec import KernelSpecManager

    folder = tmp_path_factory.mktemp("kernels")
    (folder / "plm-pin").mkdir()
    spec = {
        "argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
        "display_name": "plm_pin tests",
        "language": "python",
    }
    (folder / "plm-pin" / "kernel.json").write_text(json.dumps(spec))
    return KernelSpecManager(kernel_dirs=[str(folder)], ensure_native_kernel=False)


@pytest.mark.slow
@pytest.mark.parametrize("name", PAPERS)
def test_notebook_runs(name, kernel_specs, monkeypatch):
    """Every cell runs without error or warning in a fresh kernel, from notebooks/, with the Agg backend."""
    from jupyter_client import KernelManager
    from nbclient import NotebookClient

    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = _notebook(name)
    km = KernelManager(kernel_name="plm-pin", kernel_spec_manager=kernel_specs)
    client = NotebookClient(nb, km=km, timeout=CELL_TIMEOUT, resources={"metadata": {"path": str(NOTEBOOKS)}})
    try:
        client.execute()  # raises CellExecutionError, with the cell and its traceback, on the first error
    finally:
        if km.has_kernel:
            km.shutdown_kernel(now=True)
    stderr = [
        (k, out.text)
        for k, cell in enumerate(nb.cells)
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "stream" and out.name == "stderr"
    ]
    assert not stderr, f"{name}: cells wrote to stderr (warnings?): {stderr}"


if __name__ == "__main__":  # `make clear-notebooks`: rewrite every notebook as it is committed
    for path in sorted(NOTEBOOKS.glob("*.ipynb")):
        nbformat.write(cleared(nbformat.read(path, as_version=4)), path)
