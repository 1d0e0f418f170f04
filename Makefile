# Ramure — the two commands (make run, make test) plus make bench.
PY      ?= python3
VENV    := .venv
VPY     := $(VENV)/bin/python
STAMP   := $(VENV)/.installed
GRAMMAR ?= grammars/honda_sympodial.lsys
# make test runs the front-end tests and the library tests as two pytest processes side by side.
PYTEST  := bash .ci/test-suite.sh $(VPY)

.PHONY: run test bench venv sysdeps clean docs lint typecheck format

$(VPY):
	$(PY) -m venv $(VENV)

$(STAMP): pyproject.toml | $(VPY)
	$(VPY) -m pip install -q --upgrade pip
	$(VPY) -m pip install -q -e ".[gui,jupyter,dask,web,postgres,test,docs]"
	touch $(STAMP)

venv: $(STAMP)

# System packages for Qt/VTK under a virtual screen, Chromium, and PostgreSQL's server (the
# study tests start a throwaway cluster from it); installed only when missing and only when
# we may (root or sudo), so a developer with a display needs nothing.
sysdeps:
	@bash .ci/sysdeps.sh

run: venv
	@if [ -z "$$DISPLAY" ] && [ -z "$$WAYLAND_DISPLAY" ]; then \
	  mkdir -p out; \
	  echo "No display: rendering $(GRAMMAR) off-screen to out/ instead of opening the window."; \
	  $(VPY) -m ramure.app.cli render $(GRAMMAR) -o out/plant.png && \
	  (bash .ci/sysdeps.sh >/dev/null 2>&1 && xvfb-run -a -s "-screen 0 1400x900x24" $(VPY) -m ramure.app.desktop $(GRAMMAR) --screenshot out/window.png --quit-after 1 \
	     && echo "Wrote out/plant.png and out/window.png" || echo "Wrote out/plant.png"); \
	else \
	  $(VPY) -m ramure.app.desktop $(GRAMMAR); \
	fi

test: venv sysdeps
	$(VPY) -m ruff check .
	$(VPY) -m ruff format --check .
	@$(MAKE) --no-print-directory typecheck
	@if [ -z "$$DISPLAY" ] && command -v xvfb-run >/dev/null 2>&1; then \
	  xvfb-run -a -s "-screen 0 1400x900x24" $(PYTEST); \
	else \
	  $(PYTEST); \
	fi

# `make format` rewrites the tree in the project's style (ruff format); make test checks it.
format: venv
	$(VPY) -m ruff format .

# The documentation site: API reference from the docstrings, the grammar reference and a
# gallery built by running examples/gallery/plot_*.py; any warning fails the build.
docs: venv
	rm -rf docs/_build docs/auto_examples docs/api
	$(VPY) -m sphinx -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: docs/_build/html/index.html"

lint: venv
	$(VPY) -m ruff check .
	$(VPY) -m ruff format --check .
	@$(MAKE) --no-print-directory typecheck

# mypy cannot follow setuptools' package-dir mapping (lsys/ installs as ramure.lsys, ...), so it
# checks a mirror of the installed layout: .mypy-src/ramure/ holds symlinks to ramure/*.py and to
# each folder package-dir maps, rebuilt from pyproject.toml on every run (cheap; git ignores it;
# mypy's cache stays in .mypy_cache). Findings are printed with the repository's paths and fail
# the target.
MYPY_TREE := .mypy-src
typecheck: venv
	@rm -rf $(MYPY_TREE) && mkdir -p $(MYPY_TREE)/ramure
	@for f in ramure/*.py; do ln -s ../../$$f $(MYPY_TREE)/ramure/; done
	@$(VPY) -c 'import tomllib; m = tomllib.load(open("pyproject.toml", "rb"))["tool"]["setuptools"]["package-dir"]; print("\n".join(k.split(".")[1] + " " + v for k, v in m.items() if k.count(".") == 1))' \
	  | while read name dir; do ln -s ../../$$dir $(MYPY_TREE)/ramure/$$name; done
	@$(VPY) -m mypy > .mypy-report.txt 2>&1; rc=$$?; \
	  sed -e 's#^$(MYPY_TREE)/ramure/\([^/]*\.py\)#ramure/\1#' -e 's#^$(MYPY_TREE)/ramure/##' .mypy-report.txt \
	    | if [ $$rc -eq 0 ]; then echo "mypy: $$(tail -1)"; else cat; fi; \
	  exit $$rc

bench: venv sysdeps
	@if [ -z "$$DISPLAY" ] && command -v xvfb-run >/dev/null 2>&1; then \
	  xvfb-run -a -s "-screen 0 1400x900x24" $(VPY) benchmarks/run.py; \
	else \
	  $(VPY) benchmarks/run.py; \
	fi

clean:
	rm -rf $(VENV) out tests/artifacts .pytest_cache docs/_build docs/auto_examples docs/api
