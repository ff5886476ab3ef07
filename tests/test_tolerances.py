"""Every tolerance of plm_pin is defined in plm_pin/tolerances.py, documented there and in the guide."""

import ast
import re
from pathlib import Path

import plm_pin.tolerances as tolerances

ROOT = Path(__file__).resolve().parents[1]

TOLERANCE_NAME = re.compile(r"(^|_)(TOL|RTOL|ATOL|XTOL|EPS|MARGIN|RCOND|THRESHOLD)$")
"""Names that say "tolerance": defined in plm_pin/tolerances.py only."""

TOLERANCE_ARGUMENT = re.compile(
    r"^(tol|rtol|atol|xtol|eps|rcond|noise|near|margin)$|_(tol|rtol|atol|xtol|rcond)$"
)
"""Arguments whose default is a tolerance: a name from plm_pin.tolerances, never a literal."""

STEPS = {
    "DEFAULT_STEP",
    "MIN_STEP",
    "FD_STEP",
    "SAMPLE_STEP",
    "SIMULATION_DT",
    "SIM_DT",
    "_MIN_EXTENT",
    "_ROD",
    "_ARROW",
    "_RAIL",
    "_EDGE",
    "CAMERA_NEAR",
    "CHORD_RATIO",
}
"""Small module constants that are steps, sizes or rates, not tolerances: time steps [s], the
adaptive step below which an integrator is stuck [s], a finite-difference step [m, rad], viewer
sizes [m] and the camera's near plane [-], and the rate of convergence that lets a Newton
iteration keep its factorisation."""


def _sources() -> list[Path]:
    files = [*(ROOT / "plm_pin").rglob("*.py"), *(ROOT / "analyses").glob("*.py")]
    return [p for p in files if p.name != "tolerances.py"]


def _small_literal(node: ast.AST | None) -> bool:
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    return isinstance(node, ast.Constant) and isinstance(node.value, float) and 0.0 < node.value <= 1e-2


def _assigned_names(tree: ast.Module) -> list[tuple[str, ast.AST | None, int]]:
    """Names assigned at module or class level, with their values."""
    out = []
    bodies = [tree.body] + [n.body for n in ast.walk(tree) if isinstance(n, ast.ClassDef)]
    for body in bodies:
        for node in body:
            if isinstance(node, ast.Assign):
                out += [(t.id, node.value, node.lineno) for t in node.targets if isinstance(t, ast.Name)]
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                out.append((node.target.id, node.value, node.lineno))
    return out


def test_tolerances_are_defined_in_one_module():
    """No module but plm_pin/tolerances.py defines a tolerance (by name, or a small float constant)."""
    bad = []
    for path in _sources():
        for name, value, line in _assigned_names(ast.parse(path.read_text())):
            upper = name.lstrip("_").isupper()
            if upper and (TOLERANCE_NAME.search(name) or (_small_literal(value) and name not in STEPS)):
                bad.append(f"{path.relative_to(ROOT)}:{line} {name}")
    assert not bad, f"tolerances defined outside plm_pin/tolerances.py: {bad}"


def test_tolerance_arguments_default_to_named_tolerances():
    """A ``tol`` / ``rtol`` / ``atol`` ... argument never defaults to a literal number."""
    bad = []
    for path in _sources():
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            args = node.args
            positional = [*args.posonlyargs, *args.args]
            pairs = list(zip(positional[len(positional) - len(args.defaults) :], args.defaults, strict=True))
            pairs += [(a, d) for a, d in zip(args.kwonlyargs, args.kw_defaults, strict=True) if d is not None]
            for arg, default in pairs:
                if TOLERANCE_ARGUMENT.search(arg.arg) and _small_literal(default):
                    bad.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name}({arg.arg}=...)")
    assert not bad, f"tolerance arguments with literal defaults: {bad}"


def test_every_tolerance_is_documented_with_its_unit():
    """Each constant of plm_pin.tolerances has a docstring starting with its unit in brackets."""
    tree = ast.parse(Path(tolerances.__file__).read_text())
    body = tree.body
    names = []
    for k, node in enumerate(body):
        if isinstance(node, ast.Assign) and node.targets[0].id != "__all__":  # type: ignore[attr-defined]
            name = node.targets[0].id  # type: ignore[attr-defined]
            names.append(name)
            doc = body[k + 1] if k + 1 < len(body) else None
            assert isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant), name
            assert re.match(r"\[[^\]]+\] \S", doc.value.value), f"{name}: docstring must start with [unit]"
            assert isinstance(getattr(tolerances, name), float), name
    assert len(names) == len(set(names))
    assert not [n for n in dir(tolerances) if n.isupper() and n not in names]
    assert sorted(tolerances.__all__) == tolerances.__all__ == sorted(names)


def test_the_guide_lists_every_tolerance_with_its_value():
    """docs/guide/tolerances.md has one table row per tolerance, with the module's value."""
    page = (ROOT / "docs" / "guide" / "tolerances.md").read_text()
    rows = dict(re.findall(r"^\| `([A-Z0-9_]+)` \| ([^|]+) \|", page, re.M))
    names = [n for n in vars(tolerances) if n.isupper()]
    assert sorted(rows) == sorted(names)
    for name in names:
        assert float(rows[name].strip()) == getattr(tolerances, name), name
