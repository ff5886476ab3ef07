"""Packaging: public names resolve, and the wheel carries every preset description."""

from __future__ import annotations

import importlib
import json
import os
import pkgutil
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import plm_pin
from plm_pin.models import preset_names

REPO = Path(__file__).resolve().parents[1]


def test_every_name_in_every_all_resolves():
    """Each name listed in any package's __all__ is importable from that package."""
    for info in pkgutil.walk_packages(plm_pin.__path__, "plm_pin."):
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", []):
            assert hasattr(module, name), f"{info.name}.__all__ lists missing {name!r}"
    for name in plm_pin.__all__:
        assert hasattr(plm_pin, name)


def test_each_public_name_is_public_in_one_package_only():
    """No object is listed under one name in two __all__: it is imported from one place, documented once."""
    owners: dict[tuple[str, int], list[str]] = {}
    modules = [
        plm_pin,
        *(importlib.import_module(i.name) for i in pkgutil.walk_packages(plm_pin.__path__, "plm_pin.")),
    ]
    for module in modules:
        for name in getattr(module, "__all__", []):
            owners.setdefault((name, id(getattr(module, name))), []).append(module.__name__)
    assert {name: where for (name, _), where in owners.items() if len(where) > 1} == {}


HEAVY = (
    "scipy",
    "meshcat",
    "matplotlib",
    "jinja2",
    "dask",
    "distributed",
    "xarray",
    "zarr",
    "pyarrow",
    "pandas",
    "yourdfpy",
    "trimesh",
    "mujoco",
    "proxsuite",
    "highspy",
    "numba",
)
"""Third-party modules that ``import plm_pin`` and loading a shipped description never import."""

ABOVE_THE_LOADER = (
    "families",
    "kinematics",
    "statics",
    "dynamics",
    "stiffness",
    "workspace",
    "sweep",
    "viz",
    "report",
)
"""plm_pin packages that ``import plm_pin`` and loading a shipped description never import."""


def _modules_after(code: str) -> list[str]:
    """The names in sys.modules after running ``code`` in a fresh interpreter."""
    probe = f"import json, sys; {code}; print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def _heavy_or_above(modules: list[str]) -> list[str]:
    """The :data:`HEAVY` modules and :data:`ABOVE_THE_LOADER` packages among ``modules``."""
    heavy = {m.split(".")[0] for m in modules if m.split(".")[0] in HEAVY}
    above = {".".join(m.split(".")[:2]) for m in modules if m.split(".")[:1] == ["plm_pin"]}
    return sorted(heavy | {m for m in above if m.split(".")[-1] in ABOVE_THE_LOADER})


def test_import_loads_no_family_no_analysis_and_no_heavy_dependency():
    """`import plm_pin` loads no family, no analysis package, no scipy, matplotlib, yourdfpy, ..."""
    assert _heavy_or_above(_modules_after("import plm_pin")) == []


def test_loading_a_preset_runs_no_builder_and_no_analysis():
    """Loading a shipped description reads its URDF: no family (builder), no kinematics, no yourdfpy."""
    presets = _modules_after("import plm_pin; plm_pin.load('harada2011_3d4m'); plm_pin.load('fourbar')")
    assert _heavy_or_above(presets) == []
    urdf = REPO / "urdf" / "zhao2011_8pss.urdf"
    assert _heavy_or_above(_modules_after(f"import plm_pin; plm_pin.load({str(urdf)!r})")) == []


def test_building_a_preset_imports_its_builder_only():
    """Building a preset imports its family's builder (a string in the registry), not the planners."""
    code = "import plm_pin; plm_pin.build_mechanism('harada2015_asymmetric', validate=False)"
    loaded = _modules_after(code)
    families = [m for m in loaded if m.startswith("plm_pin.families")]
    assert families == ["plm_pin.families", "plm_pin.families.prrrp", "plm_pin.families.prrrp.builder"]
    assert not [m for m in loaded if m.startswith("plm_pin.kinematics")]


OUTSIDE = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
"""The environment of a process run outside the checkout (a PYTHONPATH naming it would reach it)."""


@pytest.fixture(scope="module")
def wheel_venv(tmp_path_factory) -> Path:
    """`pip wheel .` installed (with its required dependencies only) into a fresh venv; its bin folder.

    Installed without byte-compiling (a third of the time): Python compiles what the tests import.
    """
    tmp_path = tmp_path_factory.mktemp("wheel")
    wheels = tmp_path / "wheels"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(wheels), str(REPO)],
        check=True,
        capture_output=True,
    )
    (wheel,) = wheels.glob("plm_pin-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "--no-compile", str(wheel)],
        check=True,
        capture_output=True,
    )
    where = "import os, plm_pin; print(os.path.dirname(plm_pin.__file__))"
    installed = subprocess.run(
        [str(python), "-c", where], cwd=tmp_path, capture_output=True, text=True, check=True, env=OUTSIDE
    )
    _share_compiled_cache(Path(installed.stdout.strip()))
    return venv / "bin"


def _share_compiled_cache(installed: Path) -> None:
    """Give the package installed at ``installed`` the checkout's compiled kernels (numba's cache files).

    numba keys a cached function on its source file's modification time and size: each installed
    file identical to the checkout's gets the checkout's time and its cache files, so the installed
    package loads what the checkout's tests compiled instead of compiling every kernel again (minutes
    on a 2-core machine). A kernel the checkout has not compiled is compiled where it is installed.
    The tests using the venv run last (``tests/conftest.py``), when the checkout's cache is filled.
    """
    for source in (REPO / "plm_pin").rglob("*.py"):
        cached = sorted(source.parent.glob(f"__pycache__/{source.stem}.*.nb[ic]"))
        target = installed / source.relative_to(REPO / "plm_pin")
        if not cached or not target.is_file() or target.read_bytes() != source.read_bytes():
            continue
        stat = source.stat()
        os.utime(target, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        (target.parent / "__pycache__").mkdir(exist_ok=True)
        for file in cached:
            shutil.copy2(file, target.parent / "__pycache__" / file.name)


@pytest.mark.slow
def test_wheel_installed_outside_the_checkout_loads_every_preset(wheel_venv, tmp_path):
    """`pip wheel .` installed into a fresh venv, run outside the checkout, loads all presets."""
    python = wheel_venv / "python"
    names = preset_names()
    code = (
        "import plm_pin, sys; from pathlib import Path\n"
        f"assert not Path(plm_pin.__file__).is_relative_to({str(REPO)!r}), plm_pin.__file__\n"
        f"for n in {names!r}:\n"
        "    m = plm_pin.load(n); print(n, m.mobility, m.redundancy)\n"
    )
    out = subprocess.run([str(python), "-c", code], cwd=tmp_path, capture_output=True, text=True, env=OUTSIDE)
    assert out.returncode == 0, out.stderr
    assert [line.split()[0] for line in out.stdout.splitlines()] == names


@pytest.mark.slow
def test_installed_wheel_runs_the_command_line_and_the_overview(wheel_venv, tmp_path):
    """From a wheel outside the checkout: --version, python -m, the extra named, then report and view work."""
    bin_ = wheel_venv

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        command = [str(a) for a in args]
        return subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, env=OUTSIDE)

    assert run(bin_ / "plm-pin", "--version").stdout.strip() == f"plm-pin {plm_pin.__version__}"
    assert (
        run(bin_ / "python", "-m", "plm_pin", "--version").stdout.strip() == f"plm-pin {plm_pin.__version__}"
    )
    bare = run(bin_ / "plm-pin", "report", "fourbar", "--out", tmp_path / "reports")
    assert bare.returncode == 1
    assert bare.stderr.strip().splitlines() == [
        "error: plm_pin.report needs jinja2 and markdown-it-py, which are not installed: "
        "pip install 'plm-pin[report]'"
    ]
    subprocess.run(  # the report extra's packages (the wheel itself is already installed)
        [
            str(bin_ / "pip"),
            "install",
            "-q",
            "--no-compile",
            "jinja2",
            "markdown-it-py",
            "matplotlib",
            "meshcat",
        ],
        check=True,
        capture_output=True,
    )
    report = run(bin_ / "plm-pin", "report", "fourbar", "--out", tmp_path / "reports")
    assert report.returncode == 0, report.stderr
    assert (tmp_path / "reports" / "overview-fourbar" / "report.html").is_file()
    paper = run(bin_ / "plm-pin", "report", "harada2011", "--out", tmp_path / "reports")
    assert paper.returncode == 1
    assert "the paper studies live in the analyses/ folder of the plm_pin source checkout" in paper.stderr
    page = tmp_path / "motion.html"
    view = run(bin_ / "plm-pin", "view", "fourbar", "--animate", "overview:simulation", "--html", page)
    assert view.returncode == 0, view.stderr
    assert page.stat().st_size > 1000


@pytest.mark.slow
def test_the_wheel_ships_no_benchmark_harness(wheel_venv):
    """The installed wheel holds plm_pin/ without the benchmark harness (benchmarks/ stays in the repo)."""
    (site,) = wheel_venv.parent.glob("lib/python*/site-packages")
    assert (site / "plm_pin" / "core" / "mechanism.py").is_file()
    assert not (site / "benchmarks").exists()
    assert [p.name for p in (site / "plm_pin").rglob("*bench*")] == []
