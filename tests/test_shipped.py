"""The shipped baselines in both tools (colorsort-eval, lerobot-eval), how they execute, and the analyses of
their scores."""

import json
from pathlib import Path

import numpy as np
import pytest
from baseline_common import SHIPPED, score_row, scores
from helpers import console_script

from colorsort.cli.eval import main as eval_main


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_baseline_sorts_through_colorsort_eval(name, tmp_path):
    """README's command for a shipped policy on the first of its main variant's seeds where it placed a box, cut 2 s
    after the time its scores say it placed it: cameras come from the checkpoint, and it places that box as
    scored."""
    if not SHIPPED[name].is_dir():
        pytest.skip(f"baselines/{name} is not shipped")
    shipped = json.loads((SHIPPED[name] / "scores.json").read_text())
    recipe = shipped["recipe"]  # in sections since DAgger's rounds became a setting; flat before
    variant = recipe.get("evaluation", recipe)["main_variant"]
    largest = max(r["demos_tried"] for r in shipped["rows"])
    seed = recipe.get("training", recipe)["seeds"][0]  # the shipped policy: the largest demo set's first seed
    (scored,) = [r for r in shipped["rows"] if (r["variant"], r["demos_tried"], r["seed"]) == (variant, largest, seed)]
    # the first episode that placed a box (the first of all, for every ACT policy; diffusion's dropped its box)
    first = next(e for e in scored["per_episode"] if any(b["outcome"] == "placed" for b in e["boxes"]))
    placed_at = min(b["time"] for b in first["boxes"] if b["outcome"] == "placed")  # [s]
    report = tmp_path / "eval.json"
    assert eval_main(["--policy", str(SHIPPED[name]), "--variant", variant, "--episodes", "1", "--seed",
                      str(first["seed"]), "--episode-length", str(round(placed_at * 20) + 40),  # 20 Hz
                      "--json", str(report)]) == 0
    result = json.loads(report.read_text())
    assert result["correct"] >= 1  # it picks and places: not an untrained policy


@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_baseline_weighs_what_a_shipped_policy_may(name):
    """Every file of each policy in the folder together (the shipped one, and each training seed's kept beside it in
    ``seed<N>/``): a state policy under 20 MB, a camera policy under 50 MB, as its README says; one whose recipe
    stores float16 weights holds float16 tensors only, and its README says so."""
    import torch
    from safetensors.torch import load_file

    if not SHIPPED[name].is_dir():
        pytest.skip(f"baselines/{name} is not shipped")
    recipe = json.loads((SHIPPED[name] / "scores.json").read_text())["recipe"]
    cameras = recipe["demos"]["cameras"] if isinstance(recipe.get("demos"), dict) else recipe["cameras"]
    readme = (SHIPPED[name] / "README.md").read_text()
    training = recipe["training"] if isinstance(recipe.get("training"), dict) else {}
    weights = training.get("weights", "float32")
    for policy in [SHIPPED[name], *sorted(SHIPPED[name].glob("seed*/"))]:
        size = sum(f.stat().st_size for f in policy.iterdir() if f.is_file()) / 1e6  # [MB]
        assert size < (50 if cameras else 20)
        dtypes = {t.dtype for t in load_file(policy / "model.safetensors").values() if t.is_floating_point()}
        assert dtypes == {getattr(torch, weights)}
    assert (f"The weights are stored in {weights}" in readme) == (weights != "float32")


@pytest.mark.slow
@pytest.mark.parametrize("name", ["act-state", "act-camera-tracking"])
def test_a_shipped_baseline_runs_in_lerobot_eval(name, tmp_path):
    """README's lerobot-eval command for a shipped policy: it loads and acts, one episode of 30 steps. The state
    policy and the tracking camera policy (cameras, ensembled chunks, the tracking belt's state); the other camera
    policies take the same path (each one's cameras in a LeRobot env: test_lerobot_cli, test_snapshot)."""
    if not SHIPPED[name].is_dir():
        pytest.skip(f"baselines/{name} is not shipped")
    from colorsort.benchmark.policies import checkpoint_cameras

    cameras, size = checkpoint_cameras(SHIPPED[name])
    task = "ColorSort-Tracking-v0" if "tracking" in name else "ColorSort-Default-v0"
    done = console_script("lerobot-eval", [
        "--env.type=colorsort", f"--env.task={task}", f"--env.cameras={','.join(cameras) or 'none'}",
        f"--env.image_size={size[0] if size else 128}", f"--policy.path={SHIPPED[name]}", "--policy.device=cpu",
        "--eval.n_episodes=1", "--eval.batch_size=1", "--env.episode_length=30", f"--output_dir={tmp_path / 'eval'}"],
        tmp_path)
    assert done.returncode == 0, (done.stdout + done.stderr)[-3000:]
    overall = json.loads((tmp_path / "eval" / "eval_info.json").read_text())["overall"]
    assert overall["n_episodes"] == 1 and 0 <= overall["pc_success"] <= 100


@pytest.mark.parametrize("variant", ["robots-panda", "tracking"])
def test_a_checkpoint_on_a_variant_it_does_not_fit_gets_a_one_line_error(variant, capsys):
    """act-state takes 23 state inputs: the Panda's state has 25, a tracking belt's 24."""
    assert eval_main(["--policy", str(SHIPPED["act-state"]), "--variant", variant, "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"cannot run on {variant}" in err and "'default'" in err


def test_a_recipe_scored_on_a_variant_its_policy_cannot_run_on_gets_a_one_line_error(capsys, tmp_path):
    """The pipeline refuses before collecting anything: a stopping-belt policy cannot run on a tracking belt."""
    from colorsort.cli.baseline import main as baseline_main

    out = tmp_path / "never"
    assert baseline_main(["--recipe", "state", "--evaluation.variants=default,tracking", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "['tracking'] do not fit" in err and "'distractors'" in err
    assert not out.exists()


@pytest.mark.slow
def test_variant_all_runs_each_shipped_baseline_on_exactly_the_variants_it_fits(capsys):
    """A stopping-belt policy (23 state inputs) skips the tracking variants (24) and the Panda (25); the tracking
    policy runs on the three tracking variants only; every skipped variant is named with its reason."""
    from colorsort.cli.eval import variant_names

    tracking = ["tracking", "tracking-fast", "tracking-jitter"]
    for name, path in SHIPPED.items():
        if not path.is_dir():
            continue
        fits = variant_names(str(path), "all")
        skipped = capsys.readouterr().err
        if "tracking" in name:
            assert fits == tracking
        else:
            assert not set(fits) & {*tracking, "robots-panda"}
            assert {"seed", "default", "fast", "jitter", "lighting", "distractors"} <= set(fits)
        assert all(f"skipping {v}:" in skipped for v in ["robots-panda", *(set(tracking) - set(fits))])


@pytest.mark.slow
def test_an_execution_is_the_same_checkpoint_acting_as_named(tmp_path):
    """``with_execution``'s copy of a checkpoint executes as named: LeRobot loads it with that many open-loop steps or
    with its temporal ensembler; the weights are the shipped ones; a bad name is refused."""
    from studies.chunk_execution import inference_settings, with_execution

    from colorsort.benchmark.policies import LeRobotPolicy

    chunked = LeRobotPolicy(with_execution(SHIPPED["act-state"], "chunk5", tmp_path)).policy
    ensembled = LeRobotPolicy(with_execution(SHIPPED["act-state"], "ens0.01", tmp_path)).policy
    assert (chunked.config.n_action_steps, chunked.config.temporal_ensemble_coeff) == (5, None)
    assert ensembled.config.n_action_steps == 1 and ensembled.temporal_ensembler.chunk_size == 20
    assert (tmp_path / "chunk5" / "model.safetensors").read_bytes() == (
        SHIPPED["act-state"] / "model.safetensors").read_bytes()
    with pytest.raises(ValueError, match="chunkN"):
        inference_settings("open10")


def test_executions_are_compared_on_each_variant_named_and_on_validation_seeds_when_asked(monkeypatch):
    """``execution_table``: one row per variant and execution, each scored on that variant; ``validation`` plays the
    validation seeds (from 20000), never the evaluation seeds; an unknown variant or execution stops before any
    episode runs."""
    from types import SimpleNamespace

    from studies.chunk_execution import execution_table

    from colorsort.benchmark import evaluate as evaluation
    from colorsort.variants import VALIDATION_SEEDS

    played = []

    def fake_evaluate(policy, variant, episodes, **kwargs):
        played.append((Path(policy).name, variant, kwargs["seed"]))
        return SimpleNamespace(success_ci95=(0.0, 1.0), success_rate=1.0, correct=3, misplaced=0, dropped=0,
                               distractors_let_through=0, distractors=0)

    monkeypatch.setattr(evaluation, "evaluate", fake_evaluate)
    policy = str(SHIPPED["act-state"])
    for validation, first in ((False, None), (True, VALIDATION_SEEDS[0])):
        played.clear()
        lines = list(execution_table(policy, ["default", "distractors"], ["chunk10", "ens0.2"], 2, 1, validation))
        assert played == [(e, v, first) for v in ("default", "distractors") for e in ("chunk10", "ens0.2")]
        assert [line.split(" | ")[:2] for line in lines[3:]] == [["| default", "chunk10"], ["| default", "ens0.2"],
                                                                 ["| distractors", "chunk10"],
                                                                 ["| distractors", "ens0.2"]]
    assert "first 2 validation seeds" in lines[0]
    played.clear()
    for variants, executions, named in ((["default", "nope"], ["chunk10"], "Valid variants"),
                                        (["default"], ["open10"], "chunkN")):
        with pytest.raises(ValueError, match=named):
            list(execution_table(policy, variants, executions, 1))
    assert not played


@pytest.mark.parametrize("name", list(SHIPPED))
def test_a_shipped_scores_json_reads_as_typed_records_and_writes_back_unchanged(name):
    """Typed records: every shipped scores.json reads into ``PipelineResults`` and writes back the same JSON, so
    the records change no figure of a shipped baseline."""
    from colorsort.training.results_file import PipelineResults

    stored = json.loads((SHIPPED[name] / "scores.json").read_text())
    results = PipelineResults.from_json(stored)
    assert results.to_json() == {**stored, "curve": stored.get("curve") or []}
    assert all(r.report.episodes == len(r.report.per_episode) for r in results.rows)


def test_first_box_delay_is_the_median_over_the_seeds_both_runs_placed_a_box(tmp_path):
    """``colorsort-analyze first-box-delay``: seed 1's first placed box 0.5 s later, seed 2's 1.0 s, seed 3 placed
    nothing in one run (left out): median 0.75 s over 2 seeds; two runs with no seed in common are refused."""
    def evaluation(times: dict[int, list[tuple[float, str]]]) -> dict:
        return {"variant": "default", "mean_cycle_time_s": 4.0, "per_episode": [
            {"seed": s, "boxes": [{"time": t, "outcome": o} for t, o in boxes]} for s, boxes in times.items()]}

    new = evaluation({1: [(7.5, "placed"), (12.0, "placed")], 2: [(6.0, "dropped"), (9.0, "placed")],
                      3: [(8.0, "placed")]})
    old = evaluation({1: [(7.0, "placed")], 2: [(8.0, "placed")], 3: [(8.0, "dropped")]})
    (tmp_path / "new.json").write_text(json.dumps(new))
    (tmp_path / "old.json").write_text(json.dumps(old))
    out = console_script("colorsort-analyze", ["first-box-delay", "new.json", "old.json"], tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("first box placed +0.75 s later (median over 2 seeds, default)")
    (tmp_path / "other.json").write_text(json.dumps(evaluation({9: [(7.0, "placed")]})))
    refused = console_script("colorsort-analyze", ["first-box-delay", "new.json", "other.json"], tmp_path)
    assert refused.returncode == 2 and "no evaluation seed where both runs placed a box" in refused.stderr


def test_compare_scores_puts_two_runs_side_by_side_per_variant(tmp_path):
    """``colorsort-analyze compare``: each seed's rate, their mean, and box counts summed over the seeds; a variant only
    one run has gets a dash on the other side."""
    def row(variant: str, rate: float, correct: int, misplaced: int) -> dict:
        return score_row(demos_tried=48, variant=variant, success_rate=rate, correct=correct, misplaced=misplaced)

    new = scores([row("seed", 1.0, 40, 0), row("seed", 0.5, 20, 10), row("jitter", 0.25, 9, 6)])
    old = scores([row("seed", 0.25, 10, 12)])
    for name, run_scores in (("new.json", new), ("old.json", old)):
        (tmp_path / name).write_text(json.dumps(run_scores))
    out = console_script("colorsort-analyze", ["compare", "new.json", "old.json", "--labels", "a,b"], tmp_path)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0].startswith("| variant | a: mean (each seed) | b: mean (each seed) |")
    assert lines[2] == "| `seed` | 75% (100%, 50%) | 25% (25%) | 60 / 10 / 0 | 10 / 12 / 0 |"
    assert lines[3] == "| `jitter` | 25% (25%) | - | 9 / 6 / 0 | - |"
    assert lines[4] == "| every variant (mean of the variants' means) | 50% | 25% | | |"


def test_curves_puts_runs_learning_curves_on_one_axis_and_refuses_runs_of_different_variants(tmp_path):
    """``colorsort-analyze curves``: one curve per run on one PNG, labelled; runs whose curves are on different
    variants, a file without a curve and a wrong number of labels are refused with the reason."""
    import cv2

    def point(step: int, minutes: float, rate: float) -> dict:
        return {"step": step, "minutes": minutes, "episodes": 20, "successes": round(20 * rate),
                "success_rate": rate, "success_ci95": [max(rate - 0.2, 0.0), min(rate + 0.2, 1.0)],
                "correct": round(60 * rate), "misplaced": 0, "dropped": 0}

    def run(name: str, variant: str, curve: list[dict]) -> str:
        data = scores([score_row(demos_tried=48, variant=variant)],
                      {"demos": {"cameras": ["snapshot"]}, "evaluation": {"main_variant": variant}})
        (tmp_path / name).write_text(json.dumps({**data, "curve": curve}))
        return name

    act = run("act.json", "default", [point(1000, 10.0, 0.4), point(2000, 19.0, 1.0)])
    diffusion = run("diffusion.json", "default",
                    [point(1500, 9.5, 0.05), point(3000, 19.5, 0.3), point(4500, 29.0, 0.4)])
    out = console_script("colorsort-analyze", ["curves", act, diffusion, "--labels", "ACT,Diffusion Policy",
                                               "--out", "figs/curves.png"], tmp_path)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "wrote figs/curves.png: ACT (2 checkpoints), Diffusion Policy (3 checkpoints)"
    image = cv2.imread(str(tmp_path / "figs" / "curves.png"))
    assert image is not None and image.shape[0] > 300 and image.shape[1] > 500

    tracking = run("tracking.json", "tracking", [point(1200, 18.0, 0.0)])
    refused = console_script("colorsort-analyze", ["curves", act, tracking, "--labels", "a,b", "--out", "x.png"],
                             tmp_path)
    assert refused.returncode == 2 and "different variants (default, tracking)" in refused.stderr
    no_curve = run("none.json", "default", [])
    refused = console_script("colorsort-analyze", ["curves", act, no_curve, "--labels", "a,b", "--out", "x.png"],
                             tmp_path)
    assert refused.returncode == 2 and "no learning curve in none.json" in refused.stderr
    refused = console_script("colorsort-analyze", ["curves", act, diffusion, "--labels", "a", "--out", "x.png"],
                             tmp_path)
    assert refused.returncode == 2 and "one label per file: 2 files, 1 labels" in refused.stderr
    assert not (tmp_path / "x.png").exists()


def test_loading_a_checkpoint_prints_nothing_into_a_benchmarks_recorded_figures(capsys):
    """LeRobot's "Loading weights from local directory" stays out of stdout, which benchmarks record to docs/results."""
    from colorsort.benchmark.policies import LeRobotPolicy

    capsys.readouterr()
    LeRobotPolicy(SHIPPED["act-state"])
    assert capsys.readouterr().out == ""


def test_a_loaded_policy_skips_mode_switches_that_change_nothing_and_acts_as_before(monkeypatch):
    """``skip_unchanged_mode_switches``: ``eval()`` in eval mode walks no submodule; ``train()`` and back still set
    every one; the shipped state policy's actions over 30 steps are those of the policy as LeRobot loads it."""
    import torch

    from colorsort.benchmark.policies import LeRobotPolicy
    from colorsort.envs.gym_env import ColorSortGymEnv

    guarded, plain = LeRobotPolicy(SHIPPED["act-state"]), LeRobotPolicy(SHIPPED["act-state"])
    del plain.policy.train  # LeRobot's own: every eval() walks every submodule
    walked = []
    setattr_ = torch.nn.Module.__setattr__

    def counting(self, name, value):
        if name == "training":
            walked.append(self)
        setattr_(self, name, value)

    with monkeypatch.context() as m:
        m.setattr(torch.nn.Module, "__setattr__", counting)
        guarded.policy.eval()
        assert walked == []
        plain.policy.eval()
        assert len(walked) > 10  # what each of ACT's select_action calls costs without it
    guarded.policy.train()
    assert {m.training for m in guarded.policy.modules()} == {True}
    guarded.policy.eval()
    assert {m.training for m in guarded.policy.modules()} == {False}

    env = ColorSortGymEnv("default", cameras=(), render_mode=None)
    try:
        runs = []
        for policy in (guarded, plain):
            obs, _ = env.reset(seed=10000)
            policy.reset(env, 10000)
            actions = []
            for _ in range(30):
                actions.append(policy.act(obs))
                obs, *_ = env.step(actions[-1])
            runs.append(np.array(actions))
    finally:
        env.close()
    assert np.array_equal(runs[0], runs[1])
