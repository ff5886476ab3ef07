"""The package's import graph: no cycle, no upward arrow, no borrowed private name, the documented floors.

Every import statement counts: at module level, under ``TYPE_CHECKING`` and inside functions.
"""

import ast
import graphlib
import re
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

LAYERS = (
    "_text",
    "_version",
    "_io",
    "_lazy",
    "_linalg",
    "_yaml",
    "tolerances",
    "results",
    "exceptions",
    "warnings",
    "_arguments",
    "description",
    "schemas",
    "models",
    "core",
    "loading",
    "export",
    "legs",
    "kernels",
    "kinematics",
    "statics",
    "workspace",
    "dynamics",
    "stiffness",
    "families",
    "sweep",
    "optimize",
    "viz",
    "report",
    "cli",
    "__main__",
)
"""plm_pin's packages and top-level modules, bottom up: each imports only those before it.

The packages among them are the floors of docs/index.md's layout, in this order."""


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


def _floor(module: str) -> str:
    """The package or top-level module of plm_pin that ``module`` belongs to."""
    return module.split(".")[1]


def test_the_floors_are_the_documented_packages_and_modules():
    """plm_pin holds exactly the packages and modules of LAYERS; docs/index.md lists the packages in order."""
    packages = {p.parent.name for p in (ROOT / "plm_pin").glob("*/__init__.py")}
    modules = {p.stem for p in (ROOT / "plm_pin").glob("*.py")} - {"__init__"}
    assert sorted(packages | modules) == sorted(LAYERS)
    layout = (ROOT / "docs" / "index.md").read_text().split("plm_pin/     ", 1)[1].split("\nanalyses/", 1)[0]
    documented = re.findall(r"^  (\w+)/ ", layout, flags=re.MULTILINE)
    assert documented == [name for name in LAYERS if name in packages]


def test_every_import_points_down_the_floors():
    """A module imports only modules of its own floor or of floors below it (LAYERS order)."""
    level = {name: k for k, name in enumerate(LAYERS)}
    upward = sorted(
        (module, target)
        for module, targets in _graph().items()
        if module != "plm_pin"  # the top level re-exports the core names
        for target in targets
        if level[_floor(target)] > level[_floor(module)]
    )
    assert upward == []


def _owner(module: str, name: str | None = None) -> str | None:
    """The package a private module (``_x``) in ``module``'s path, or a private ``name``, belongs to."""
    parts = module.split(".")
    for k, part in enumerate(parts):
        if part.startswith("_") and not part.startswith("__"):
            return ".".join(parts[:k])
    if name is not None and name.startswith("_") and not name.startswith("__"):
        return ".".join(parts[:-1]) if len(parts) > 1 else module
    return None


def _private_imports(folder: str) -> list[tuple[str, str]]:
    """(importer, imported) for every private module or name imported from outside its package."""
    out = []
    for path in (ROOT / folder).rglob("*.py"):
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        name = ".".join(parts[:-1] if is_package else parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                pairs = [(a.name, None) for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = name.split(".") if is_package else name.split(".")[:-1]
                if node.level:
                    base = base[: len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                pairs = [(target, a.name) for a in node.names]
            else:
                continue
            for target, imported in pairs:
                if not target.startswith("plm_pin") and not target.startswith(parts[0]):
                    continue
                owner = _owner(target, imported)
                if imported is not None and owner is None:  # "from package import _module"
                    owner = _owner(f"{target}.{imported}")
                if owner is not None and not (name + ".").startswith(owner + "."):
                    out.append((name, f"{target}:{imported}" if imported else target))
    return sorted(out)


def test_no_module_borrows_a_private_name_of_another_package():
    """A ``_name`` (module, function, class or constant) is used only inside the package that holds it."""
    assert _private_imports("plm_pin") == []
    assert _private_imports("analyses") == []
