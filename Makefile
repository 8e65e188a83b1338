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
	$(VENV)/bin/colorsort-collect --episodes 4 --out datasets/demo --repo-id local/colorsort-demo --overwrite
	$(VENV)/bin/colorsort-replay datasets/demo --episode 0 --size 480x640 --video outputs/demo_episode0.mp4
	$(VENV)/bin/colorsort-eval --policy expert --variant default --episodes 3 --json outputs/eval_expert_default.json
	@echo
	@echo "demo outputs:"
	@echo "  outputs/sort.mp4, outputs/sort.png    the expert sorting 6 boxes (video, contact sheet), outputs/sort.json"
	@echo "  datasets/demo/                        a LeRobot v3.0 dataset of 4 pick-and-place episodes"
	@echo "  outputs/demo_episode0.mp4, .png       its episode 0 replayed from the stored states at 640x480"
	@echo "  outputs/eval_expert_default.json      the expert on the benchmark's default variant (3 episodes)"

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q tests

bench: $(STAMP)
	$(VENV)/bin/python demos/bench_env.py
	$(VENV)/bin/python demos/bench_perception.py --views 1000
	$(VENV)/bin/python demos/bench_sort.py --preset default --seeds 10 --boxes 20
	$(VENV)/bin/python demos/bench_sort.py --preset seed --seeds 3 --boxes 4
	$(VENV)/bin/python demos/bench_collect.py --episodes 48
	$(VENV)/bin/python demos/bench_suite.py --episodes 10

clean:
	rm -rf $(VENV) build *.egg-info outputs datasets/demo
