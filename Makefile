# Two commands do everything on a fresh Debian machine with Python 3.11:
#   make demo   set up .venv (Debian packages + pinned Python packages), run the demo
#   make test   same set-up, then the test suite
#   make docs   same set-up, then the HTML documentation in build/docs
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# libegl1 libegl-mesa0 libgl1-mesa-dri: an off-screen OpenGL context for the viewer's screenshot test
DEB_PACKAGES := libsuitesparse-dev libopenblas0-pthread libgomp1 libegl1 libegl-mesa0 libgl1-mesa-dri
OUT ?= demo_output

.PHONY: demo test test-all docs lint bench report clean setup claims claims-full

setup: $(STAMP)

$(STAMP): pyproject.toml requirements.lock
	@missing=""; for p in $(DEB_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || missing="$$missing $$p"; done; \
	if [ -n "$$missing" ]; then \
	  echo "Installing Debian packages:$$missing"; \
	  SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements.lock
	$(PY) -m pip install -q --no-deps -e .
	$(PY) -c "from cvxgeodesic.strategies.warm_up import warm_up; warm_up()"  # compile the solver kernels once (Numba cache)
	@touch $(STAMP)

# every time and accuracy figure README.md and docs/ quote, measured on this machine beside the quoted value
# (one thread; needs ../shared/meshes). claims: a subset of the meshes, under 10 min on 2 cores;
# claims-full: every shared mesh each figure concerns. CLAIMS_OUT=docs/claims.md also writes the dated page.
claims: $(STAMP)
	$(PY) benchmarks/claims.py --quick $(if $(CLAIMS_OUT),--out $(CLAIMS_OUT))

claims-full: $(STAMP)
	$(PY) benchmarks/claims.py $(if $(CLAIMS_OUT),--out $(CLAIMS_OUT))

demo: $(STAMP)
	$(VENV)/bin/cvxgeodesic demo --out $(OUT)

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy
	$(PY) -m pytest -m "not slow" -q

# the API reference (numpydoc docstrings) and the Markdown pages of docs/, as HTML; a warning fails the build
docs: $(STAMP)
	@$(PY) -m sphinx -W --keep-going -q -b html docs build/docs

test-all: $(STAMP)
	$(PY) -m pytest -q

bench: $(STAMP)
	$(PY) benchmarks/solver_speed.py

report: $(STAMP)
	$(PY) benchmarks/report.py --out docs

clean:
	rm -rf $(VENV) $(OUT) build dist src/*.egg-info .pytest_cache .ruff_cache .mypy_cache
