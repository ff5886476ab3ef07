# plm_pin: `make report` and `make test` do all set-up on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.plm-pin-installed
REPORTS ?= reports

.PHONY: all setup test test-fast browser phcpack report docs lint format bench urdf clear-notebooks clean

all: test

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

setup: $(STAMP)

# The tests run on 2 pytest-xdist workers (CI has 2 cores), each with one BLAS thread: more threads
# only fight over the cores on the small matrices here. tests/conftest.py groups the tests so that
# `report all` and each module fixture (docs build, wheel venv) run once, the longest first.
PYTEST := OPENBLAS_NUM_THREADS=1 $(PY) -m pytest -n 2

test: $(STAMP) browser phcpack
	$(PYTEST)

# The browser check (tests/report/test_browser.py) drives Debian's chromium with chromium-driver.
# Installed here when missing, as root or with passwordless sudo; otherwise the check fails and
# says how to install them (PLM_PIN_SKIP_BROWSER=1 skips it on purpose, except on CI).
BROWSER_PACKAGES := chromium chromium-driver fonts-liberation
browser:
	@if { [ "$$PLM_PIN_SKIP_BROWSER" != 1 ] || [ -n "$$CI" ]; } \
	    && ! { command -v chromium && command -v chromedriver; } >/dev/null; then \
	  if [ "$$(id -u)" -eq 0 ]; then sudo=; \
	  elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then sudo="sudo -n"; \
	  else echo "make: chromium/chromedriver missing and no root: the browser check will fail;" \
	    "sudo apt-get install $(BROWSER_PACKAGES)" >&2; exit 0; fi; \
	  if ! command -v apt-get >/dev/null; then \
	    echo "make: no apt-get: install chromium and chromedriver yourself; the browser check will fail" >&2; \
	  elif ! { $$sudo apt-get update -qq && $$sudo env DEBIAN_FRONTEND=noninteractive \
	      apt-get install -y -qq --no-install-recommends $(BROWSER_PACKAGES) >/dev/null; }; then \
	    echo "make: installing $(BROWSER_PACKAGES) failed; the browser check will fail" >&2; fi; \
	fi

# The PHCpack oracle of the complete forward kinematics (tests/kinematics/homotopy/phc_stewart.py, a
# slow test) runs in Debian's python3-phcpy, with the system python3 (not the venv). Installed here
# when missing, as the browser packages are; otherwise the oracle test is skipped (it fails on CI).
phcpack:
	@if ! /usr/bin/python3 -c "import phcpy" >/dev/null 2>&1; then \
	  if [ "$$(id -u)" -eq 0 ]; then sudo=; \
	  elif command -v sudo >/dev/null && sudo -n true 2>/dev/null; then sudo="sudo -n"; \
	  else echo "make: python3-phcpy missing and no root: the PHCpack oracle test is skipped;" \
	    "sudo apt-get install python3-phcpy" >&2; exit 0; fi; \
	  if ! command -v apt-get >/dev/null; then \
	    echo "make: no apt-get: the PHCpack oracle test is skipped" >&2; \
	  elif ! { $$sudo apt-get update -qq && $$sudo env DEBIAN_FRONTEND=noninteractive \
	      apt-get install -y -qq --no-install-recommends python3-phcpy >/dev/null; }; then \
	    echo "make: installing python3-phcpy failed; the PHCpack oracle test is skipped" >&2; fi; \
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
