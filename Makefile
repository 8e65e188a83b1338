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
	$(VENV)/bin/python demos/run_cell.py --seconds 60 --out outputs

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q tests

bench: $(STAMP)
	$(VENV)/bin/python demos/bench_env.py

clean:
	rm -rf $(VENV) build *.egg-info outputs
