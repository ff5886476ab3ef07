# plm_pin: `make report` and `make test` do all set-up on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.plm-pin-installed
REPORTS ?= reports

.PHONY: all setup test test-fast system-packages report docs lint format bench urdf clear-notebooks clean

all: test

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

# The tests run on 2 pytest-xdist workers (CI has 2 cores), each with one BLAS thread: more threads
# only fight over the cores on the small matrices here. tests/conftest.py groups the tests so that
# `report all` and each module fixture (docs build, wheel venv) run once, the longest first, and
# first compiles the numba kernels once, in two processes (tests/compile_kernels.py), so that the
# workers load them from the disk cache rather than each compile them (a fresh clone: 621 -> 487 s).
PYTEST := OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -n 2

test: $(STAMP) system-packages
	$(PYTEST)

# Debian packages some tests drive, installed here when missing (as root or with passwordless sudo):
# chromium with chromium-driver for the browser checks (tests/report/test_browser.py, the live
# inspector), and python3-phcpy, PHCpack for the system python3, the independent oracle of the complete
# forward kinematics (tests/kinematics/homotopy/phc_stewart.py). When they cannot be installed,
# the make step says so and the checks fail on CI; elsewhere PLM_PIN_SKIP_BROWSER=1 skips the browser
# checks on purpose and the PHCpack oracle is skipped where phcpy is missing.
SYSTEM_PACKAGES := chromium chromium-driver fonts-liberation python3-phcpy
system-packages:
	@if ! { command -v chromium && command -v chromedriver && /usr/bin/python3 -c "import phcpy"; } \
	    >/dev/null 2>&1; then \
	  if [ "$$(id -u)" -eq 0 ]; then sudo=; \
	  elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then sudo="sudo -n"; \
	  else echo "make: chromium, chromedriver or python3-phcpy missing and no root: their checks will" \
	    "fail or be skipped; sudo apt-get install $(SYSTEM_PACKAGES)" >&2; exit 0; fi; \
	  if ! command -v apt-get >/dev/null; then \
	    echo "make: no apt-get: install $(SYSTEM_PACKAGES) yourself; their checks will fail or be skipped" >&2; \
	  elif ! { $$sudo apt-get update -qq && $$sudo env DEBIAN_FRONTEND=noninteractive \
	      apt-get install -y -qq --no-install-recommends $(SYSTEM_PACKAGES) >/dev/null; }; then \
	    echo "make: installing $(SYSTEM_PACKAGES) failed; their checks will fail or be skipped" >&2; fi; \
	fi

test-fast: $(STAMP)
	$(PYTEST) -m "not slow" -x -q

report: $(STAMP)
	$(VENV)/bin/plm-pin report all --out $(REPORTS)

# The docs site (Sphinx + MyST, tutorials executed): warnings are errors. `make test` builds it too
# (tests/test_docs.py), into a temporary folder, and checks its internal links.
docs: $(STAMP)
	$(PY) -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "open docs/_build/html/index.html"

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .
	$(VENV)/bin/mypy

format: $(STAMP)
	$(VENV)/bin/ruff format .
	$(VENV)/bin/ruff check --fix .

bench: $(STAMP)
	$(PY) -m benchmarks.harness --out $(REPORTS)/bench --docs docs/_generated/benchmarks.md

urdf: $(STAMP)
	$(PY) -m plm_pin.models.generate

# Notebooks are committed without outputs: run this after saving one from Jupyter.
clear-notebooks: $(STAMP)
	$(PY) tests/test_notebooks.py

clean:
	rm -rf $(VENV) $(REPORTS) .pytest_cache .mypy_cache .ruff_cache build dist docs/_build
	find plm_pin -name '*.nbi' -delete -o -name '*.nbc' -delete  # numba's compiled kernels
