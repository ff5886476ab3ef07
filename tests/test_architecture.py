"""The package's import graph: no cycle between plm_pin's modules, nor between its packages.

Every import statement counts: at module level, under ``TYPE_CHECKING`` and inside functions.
"""

import ast
import graphlib
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _modules() -> dict[str, tuple[Path, bool]]:
    out = {}
    for path in (ROOT / "plm_pin").rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        out[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return out


def _graph() -> dict[str, set[str]]:
    """Module -> the plm_pin modules it imports (its own parent packages left out)."""
    modules = _modules()
    edges: dict[str, set[str]] = defaultdict(set)
    for name, (path, is_package) in modules.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = name.split(".") if is_package else name.split(".")[:-1]
                if node.level:
                    base = base[: len(base) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                else:
                    module = node.module or ""
                targets = [module] + [f"{module}.{a.name}" for a in node.names]
            else:
                continue
            for target in targets:
                if target in modules and target != name and not name.startswith(target + "."):
                    edges[name].add(target)
    return edges


def _package(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:3] if len(parts) > 2 and parts[1] == "families" else parts[:2])


def test_no_module_imports_itself_through_others():
    graphlib.TopologicalSorter(_graph()).prepare()  # raises CycleError naming the cycle


def test_no_package_imports_itself_through_others():
    packages: dict[str, set[str]] = defaultdict(set)
    for module, targets in _graph().items():
        for target in targets:
            a, b = _package(module), _package(target)
            if a != b and not a.startswith(b + ".") and not b.startswith(a + "."):
                packages[a].add(b)
    graphlib.TopologicalSorter(packages).prepare()


def test_the_core_imports_no_analysis():
    """plm_pin.core sits below every analysis package: it imports none of them."""
    above = (
        "kinematics",
        "statics",
        "dynamics",
        "workspace",
        "stiffness",
        "families",
        "models",
        "viz",
        "report",
        "sweep",
    )
    bad = {
        m: sorted(t for t in ts if t.split(".")[1] in above)
        for m, ts in _graph().items()
        if m.startswith("plm_pin.core")
    }
    assert not {m: t for m, t in bad.items() if t}
