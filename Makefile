# Two commands do all set-up on a fresh machine (Python >= 3.10 with venv and pip):
#   make run    start the app on the shipped default scene
#   make test   run the whole test suite, the browser tests included (make lint: ruff alone)
VENV   ?= .venv
PY     := $(VENV)/bin/python
ARGS   ?=

.PHONY: run test lint bench install chromium

run: $(VENV)/.installed
	$(PY) serve.py $(ARGS)

test: $(VENV)/.installed-test chromium
	$(PY) -m pytest $(ARGS)

lint: $(VENV)/.installed-test
	$(PY) -m ruff check .

bench: $(VENV)/.installed-test chromium
	$(PY) bench/bench_match.py
	$(PY) bench/bench_heading.py
	$(PY) bench/bench_loaders.py
	$(PY) bench/bench_baselines.py
	$(PY) bench/bench_accuracy.py
	$(PY) bench/bench_app.py
	$(PY) bench/bench_start.py

install: $(VENV)/.installed

$(VENV)/.installed: pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e .
	touch $@

$(VENV)/.installed-test: $(VENV)/.installed
	$(PY) -m pip install -q -e '.[test]'
	touch $@

# Playwright cannot download its own browser here: use Debian's chromium.
chromium:
	@command -v chromium >/dev/null 2>&1 || { \
	  echo "installing Debian's chromium for the browser tests"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium; }
