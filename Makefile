# Two commands do everything on a fresh machine: `make demo` and `make test`.
# The virtual environment is rebuilt only when setup.py or overrides.txt change.
PY ?= python3
VENV := .venv
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export HF_HUB_OFFLINE := 1

.PHONY: install demo test bench clean

install: $(STAMP)

$(STAMP): setup.py overrides.txt
	test -x $(VENV)/bin/python || $(PY) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip uv
	$(VENV)/bin/uv pip install --python $(VENV)/bin/python -e ".[dev]" --override overrides.txt
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/colorsort-sort --boxes 6 --seed 0 --video outputs/sort.mp4 --json outputs/sort.json

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q tests

bench: $(STAMP)
	$(VENV)/bin/python demos/bench_env.py
	$(VENV)/bin/python demos/bench_perception.py --views 1000
	$(VENV)/bin/python demos/bench_sort.py --preset default --seeds 10 --boxes 20
	$(VENV)/bin/python demos/bench_sort.py --preset seed --seeds 3 --boxes 4

clean:
	rm -rf $(VENV) build *.egg-info outputs
