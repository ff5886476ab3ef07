"""The reliability page of the guide gives the counts this suite really tries (recomputed here)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from tests.robustness.conftest import EXAMPLES, REPO

CLASSES = {
    "test_yaml.py": "YAML denial of service (alias bombs, size caps, huge values, tags)",
    "test_bodies.py": "non-physical bodies (masses, inertias, builders)",
    "test_descriptions.py": "wrong descriptions (self-closures, cycles, limits, mimics, axes, erd: names)",
    "test_cli_errors.py": "command-line errors and failing disks",
    "test_api_arguments.py": "API argument types and values",
    "test_faults.py": "faults (killed report swaps, sweep locks, corrupt checkpoints)",
    "test_builders.py": "builder parameters (lengths not > 0, negative masses, impossible geometry)",
    "test_options.py": "option types and ranges (tolerances, counts, flags, mappings, results, loads)",
    "test_singular_poses.py": "singular configurations flagged alike (a four-bar's inverse singularity)",
}
"""The module of each class of the robustness suite, as docs/guide/reliability.md names it."""

COLLECT = r"""
import json, sys, pytest
counts = {}
class Tally:
    def pytest_collection_modifyitems(self, items):
        for item in items:
            module = item.nodeid.split("::")[0].rsplit("/", 1)[-1]
            hyp = bool(getattr(getattr(item, "function", None), "is_hypothesis_test", False))
            cases, props = counts.get(module, (0, 0))
            counts[module] = (cases + (not hyp), props + hyp)
pytest.main(["--collect-only", "-q", "-p", "no:randomly", "tests/robustness"], plugins=[Tally()])
print("COUNTS", json.dumps(counts))
"""


def suite_counts() -> dict[str, tuple[int, int]]:
    """Per module: (table-driven cases, property-based tests), from pytest's own collection."""
    done = subprocess.run(
        [sys.executable, "-c", COLLECT], cwd=REPO, capture_output=True, text=True, timeout=300, check=True
    )
    line = next(line for line in done.stdout.splitlines() if line.startswith("COUNTS "))
    return {module: (cases, props) for module, (cases, props) in json.loads(line[len("COUNTS ") :]).items()}


def readme_rows(counts: dict[str, tuple[int, int]]) -> list[str]:
    """The reliability table rows the counts give (variants = cases + property tests x EXAMPLES)."""
    rows = []
    for module, label in CLASSES.items():
        cases, props = counts[module]
        rows.append(f"| {label} | {cases} | {props} | {cases + props * EXAMPLES} |")
    return rows


@pytest.mark.slow
def test_the_readme_counts_are_the_suites():
    """Each row of the guide's reliability table matches what pytest collects in tests/robustness."""
    counts = suite_counts()
    assert set(counts) - {"test_readme_counts.py"} == set(CLASSES)
    page = (REPO / "docs" / "guide" / "reliability.md").read_text(encoding="utf-8")
    for row in readme_rows(counts):
        assert row in page, row
    total = sum(c + p * EXAMPLES for m, (c, p) in counts.items() if m in CLASSES)
    assert re.search(rf"\b{total} variants\b", page), total


if __name__ == "__main__":  # print the rows for docs/guide/reliability.md
    found = suite_counts()
    print("\n".join(readme_rows(found)))
    print(sum(c + p * EXAMPLES for m, (c, p) in found.items() if m in CLASSES), "variants")
