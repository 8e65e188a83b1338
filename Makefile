# Two commands do everything on a fresh machine: `make demo` and `make test`.
# The virtual environment is rebuilt only when setup.py or overrides.txt change.
# LeRobot 0.6 needs Python >= 3.12: tools/find-python finds one (or says how to get one);
# `make test PY=/path/to/python3.12` names it.
PY ?= $(shell sh tools/find-python 2>/dev/null)
VENV := .venv
PLUGIN := plugins/lerobot_env_colorsort
STAMP := $(VENV)/.installed
export MUJOCO_GL ?= egl
export HF_HUB_OFFLINE := 1

.PHONY: install demo test test-fast lint bench baseline clean

install: $(STAMP)

$(STAMP): setup.py pyproject.toml overrides.txt $(PLUGIN)/pyproject.toml
	@test -n "$(PY)" || sh tools/find-python
	@# a .venv from an older Python (3.11, before LeRobot 0.6) is rebuilt
	$(VENV)/bin/python -c 'import sys; sys.exit(sys.version_info < (3, 12))' 2>/dev/null || rm -rf $(VENV)
	test -x $(VENV)/bin/python || $(PY) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip uv
	@# --compile-bytecode (68 s against 17 s, warm uv cache) is needed: without it every process compiles what it
	@# imports (multiprocessing's forkserver runs with -B and never writes the .pyc), a fresh clone's suite took 22
	@# instead of 14 minutes, and compiling robosuite prints a SyntaxWarning into the console scripts' output
	$(VENV)/bin/uv pip install --python $(VENV)/bin/python --compile-bytecode -e ".[dev,viz,diffusion,gpu]" -e $(PLUGIN) \
		--override overrides.txt
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/colorsort-sort --boxes 6 --seed 0 --video outputs/sort.mp4 --json outputs/sort.json
	$(VENV)/bin/colorsort-collect --episodes 4 --out datasets/demo --repo-id local/colorsort-demo --overwrite
	$(VENV)/bin/colorsort-replay datasets/demo --episode 0 --size 480x640 --video outputs/demo_episode0.mp4
	$(VENV)/bin/colorsort-eval --policy expert --variant default --episodes 3 --json outputs/eval_expert_default.json \
		--report outputs/eval_expert_default --overwrite
	@echo
	@echo "demo outputs:"
	@echo "  outputs/sort.mp4, outputs/sort.png    the expert sorting 6 boxes (video, contact sheet), outputs/sort.json"
	@echo "  datasets/demo/                        a LeRobot v3.0 dataset of 4 pick-and-place episodes"
	@echo "  outputs/demo_episode0.mp4, .png       its episode 0 replayed from the stored states at 640x480"
	@echo "  outputs/eval_expert_default.json      the expert on the benchmark's default variant (3 episodes)"
	@echo "  outputs/eval_expert_default/index.html  the same as a page to open in a browser, a video per episode"

lint: $(STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

# two pytest workers (the machines have 2 cores; a third, measured, made the suite no faster and loaded the Ray
# tests' start-up); --dist loadfile keeps each module in one worker, so module fixtures are built once and only one
# Ray cluster runs at a time; --no-loadscope-reorder: the longest modules first (tests/conftest.py's LONGEST_FIRST)
PYTEST := $(VENV)/bin/python -m pytest -q -n 2 --dist loadfile --no-loadscope-reorder

test: lint
	$(PYTEST) tests

# the tests not marked slow (pytest.ini says which those are)
test-fast: lint
	$(PYTEST) -m "not slow" tests

# the benchmarks of the cell, the expert, recording, scaling and evaluation; each writes what it prints to
# docs/results/<script>_<arguments>.md, which the docs pages link (records of one-off studies: docs/studies/)
bench: $(STAMP)
	$(VENV)/bin/python benchmarks/bench_env.py
	$(VENV)/bin/python benchmarks/bench_profile.py
	$(VENV)/bin/python benchmarks/bench_perception.py --views 1000
	$(VENV)/bin/python benchmarks/bench_colours.py
	$(VENV)/bin/python benchmarks/bench_seal.py
	$(VENV)/bin/python benchmarks/bench_sort.py --preset default --seeds 10 --boxes 20 --workers 2
	$(VENV)/bin/python benchmarks/bench_sort.py --preset seed --seeds 3 --boxes 4
	$(VENV)/bin/python benchmarks/bench_sort.py --robot Panda --seeds 2 --boxes 10
	$(VENV)/bin/python benchmarks/bench_sort.py --robot UR5e --seeds 2 --boxes 10
	$(VENV)/bin/python benchmarks/bench_tracking.py --seeds 10 --boxes 20 --workers 2
	$(VENV)/bin/python benchmarks/bench_bound.py
	$(VENV)/bin/python benchmarks/bench_bound.py --acceleration 15 --jerk 150
	$(VENV)/bin/python benchmarks/bench_bound.py --jerk 5000
	$(VENV)/bin/python benchmarks/bench_bound.py --touch-speed 0.12 --lift 0.12
	$(VENV)/bin/python benchmarks/bench_bound.py --touch-speed 0.24
	$(VENV)/bin/python benchmarks/bench_bound.py --drop-slots 4
	$(VENV)/bin/python benchmarks/bench_bound.py --drop-slots 4 --wait-at-wait-pose
	$(VENV)/bin/python benchmarks/soak.py --preset tracking-fast --boxes 2000
	$(VENV)/bin/python benchmarks/bench_tracking.py --presets default,tracking --robot Panda --seeds 2 --boxes 10
	$(VENV)/bin/python benchmarks/bench_tracking.py --presets default,tracking --robot UR5e --seeds 2 --boxes 10
	$(VENV)/bin/python benchmarks/bench_collect.py --episodes 48
	$(VENV)/bin/python benchmarks/bench_scale.py --episodes 16 --repeats 3 --eval-episodes 8
	$(VENV)/bin/python benchmarks/bench_forward.py --policies baselines/act-camera-tracking,baselines/act-camera,baselines/act-camera-snapshot,baselines/diffusion-camera-snapshot
	$(VENV)/bin/python benchmarks/bench_eval.py --policies baselines/act-camera-tracking@tracking --episodes 32 --lerobot 8
	$(VENV)/bin/python benchmarks/bench_eval.py --policies baselines/diffusion-camera-snapshot --episodes 32
	$(VENV)/bin/python benchmarks/bench_eval.py --policies expert,baselines/act-state,baselines/act-camera-snapshot,baselines/act-camera --episodes 32
	$(VENV)/bin/python benchmarks/bench_suite.py --episodes 10
	$(VENV)/bin/python benchmarks/bench_sweep.py
	$(VENV)/bin/python benchmarks/bench_ci.py
	$(VENV)/bin/python benchmarks/bench_ci.py --only compile
	$(VENV)/bin/python benchmarks/bench_render_parity.py
	$(VENV)/bin/python benchmarks/bench_render_parity.py --variant lighting
	$(VENV)/bin/python benchmarks/bench_warp_agreement.py --policy baselines/act-state --episodes 50 --episode-length 600
	$(VENV)/bin/python benchmarks/bench_warp.py --device cpu --worlds 2,16 --steps 3 --render-worlds 2 --cpu-procs 2 --cold

# a learned baseline: demos, lerobot-train, colorsort-eval, learning curve (`make baseline RECIPE=camera-tracking`;
# `colorsort-baseline --list` names the recipes); about 1.5 h a recipe on 2 CPU cores
RECIPE ?= camera
baseline: $(STAMP)
	$(VENV)/bin/colorsort-baseline --recipe $(RECIPE)

clean:
	rm -rf $(VENV) build *.egg-info outputs datasets/demo
