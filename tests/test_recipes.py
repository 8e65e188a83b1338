"""The learned baselines' recipes as configuration: sections, generated flags, perturbations, cache keys, and
the scores tables written from scores.json."""

import json

import pytest
from baseline_common import REPO, SHIPPED, baseline, run, score_row, scores
from helpers import console_script, exit_status

from colorsort.cli import baseline as colorsort_baseline
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.data.perturbations.late_pick import LatePick
from colorsort.training import cache
from colorsort.training.recipes import RECIPES, get_recipe


def test_the_diffusion_recipe_asks_lerobot_train_for_a_small_from_scratch_encoder(tmp_path):
    """Its command line: LeRobot's diffusion type, GroupNorm, no pretrained weights (a download), one shared
    encoder, a crop of 0.9 of the recipe's image side; its settings refuse what LeRobot would reject later."""
    from colorsort.cli.baseline import main
    from colorsort.training.pipeline_stages import train_command
    from colorsort.training.policy_config import DiffusionConfig

    recipe = get_recipe("camera-diffusion")
    cmd = train_command(recipe, tmp_path / "demos-48", 5000, 1000, tmp_path / "run")
    for arg in ("--policy.type=diffusion", "--policy.use_group_norm=true", "--policy.pretrained_backbone_weights=null",
                "--policy.use_separate_rgb_encoder_per_camera=false", "--policy.crop_shape=[58,58]",
                "--policy.down_dims=[64,128]", "--policy.n_obs_steps=1", "--policy.num_inference_steps=10"):
        assert arg in cmd
    assert "--policy.crop_shape=[29,29]" in train_command(get_recipe("camera-diffusion", {"demos.image_size": 32}),
                                                          tmp_path, 1, 1, tmp_path)
    assert recipe.policy.execution == "chunk8-ddim10" and recipe.label.startswith("Diffusion Policy, ")
    assert not any(a.startswith("--policy.type=act") or "dim_model" in a for a in cmd)
    with pytest.raises(ValueError, match="multiple of"):
        DiffusionConfig(horizon=10)
    with pytest.raises(ValueError, match="n_action_steps"):
        DiffusionConfig(n_action_steps=17)
    with pytest.raises(ValueError, match="crop_fraction"):
        DiffusionConfig(crop_fraction=0.2)
    assert exit_status(main, ["--recipe", "camera-diffusion", "--policy.lr_schedule=cosine",
                              "--out", str(tmp_path)]) == 2


def test_the_diffusion_recipe_takes_its_denoiser_settings_and_names_its_evaluations_by_them(tmp_path):
    """What the U-Net predicts, the schedulers and the rate reach ``lerobot-train``; the scheduler and the denoising
    steps are inference settings (a new run folder only for what changes the weights), and the evaluation's file
    name carries them, so that an evaluation under other ones is never reused; bad values name the valid ones."""
    from colorsort.training.pipeline_stages import train_command, train_settings
    from colorsort.training.policy_config import DiffusionConfig

    preset = get_recipe("camera-diffusion")
    for arg in ("--policy.prediction_type=sample", "--policy.noise_scheduler_type=DDIM",
                "--policy.optimizer_lr=0.0003", "--policy.scheduler_warmup_steps=200",
                "--policy.num_train_timesteps=100"):
        assert arg in train_command(preset, tmp_path / "demos-48", 4000, 1001, tmp_path / "run")
    recipe = colorsort_baseline.chosen_recipe(["--recipe", "camera-diffusion", "--policy.prediction_type=epsilon",
                                               "--policy.noise_scheduler_type=DDPM", "--policy.optimizer_lr=1e-4",
                                               "--policy.scheduler_warmup_steps=500"])
    cmd = train_command(recipe, tmp_path / "demos-48", 4000, 1001, tmp_path / "run")
    for arg in ("--policy.prediction_type=epsilon", "--policy.noise_scheduler_type=DDPM",
                "--policy.optimizer_lr=0.0001", "--policy.scheduler_warmup_steps=500"):
        assert arg in cmd
    ddim = recipe.override({"policy.noise_scheduler_type": "DDIM"})
    assert cache.key(train_settings(ddim)) == cache.key(train_settings(recipe))  # the same training
    assert cache.key(train_settings(preset)) != cache.key(train_settings(recipe))
    assert (recipe.policy.execution, ddim.policy.execution) == ("chunk8-ddpm10", "chunk8-ddim10")
    assert ddim.policy.inference()["noise_scheduler_type"] == "DDIM"
    with pytest.raises(ValueError, match=r"valid types are \['epsilon', 'sample'\]"):
        DiffusionConfig(prediction_type="v_prediction")
    with pytest.raises(ValueError, match=r"valid schedulers are \['DDPM', 'DDIM'\]"):
        DiffusionConfig(noise_scheduler_type="PNDM")
    with pytest.raises(ValueError, match="num_inference_steps=20: give 1 to num_train_timesteps"):
        DiffusionConfig(num_train_timesteps=10, num_inference_steps=20)


def test_a_learning_rate_reaches_lerobot_train_for_act_and_names_its_runs_apart(tmp_path):
    """``--policy.optimizer_lr``: ACT's rate in the ``lerobot-train`` command and a run folder of its own (a run at
    another rate is never reused); a policy without the field has no such flag."""
    from colorsort.training.pipeline_stages import train_command, train_settings

    recipe = colorsort_baseline.chosen_recipe(["--recipe", "camera", "--policy.optimizer_lr=3e-4",
                                               "--policy.optimizer_lr_backbone=3e-4"])
    cmd = train_command(recipe, tmp_path / "demos-48", 4000, 1001, tmp_path / "run")
    assert "--policy.optimizer_lr=0.0003" in cmd and "--policy.optimizer_lr_backbone=0.0003" in cmd
    assert cache.key(train_settings(recipe)) != cache.key(train_settings(get_recipe("camera")))
    assert exit_status(colorsort_baseline.main, ["--recipe", "camera-diffusion", "--policy.optimizer_lr_backbone=3e-4",
                                                 "--out", str(tmp_path)]) == 2


def test_loader_processes_reach_lerobot_train_and_the_shipped_recipes_keep_one(tmp_path):
    """``--training.num_workers``: lerobot-train's data-loading processes (the shipped recipes' 1, so their cache keys
    are what they were); 0 loads in the training process; a negative count is refused naming the valid ones."""
    from colorsort.training.pipeline_stages import train_command

    recipe = colorsort_baseline.chosen_recipe(["--recipe", "state", "--training.num_workers=0"])
    assert "--num_workers=0" in train_command(recipe, tmp_path / "demos", 10, 1000, tmp_path / "run")
    assert "--num_workers=1" in train_command(get_recipe("camera"), tmp_path / "demos", 10, 1000, tmp_path / "run")
    with pytest.raises(ValueError, match="num_workers=-1: give 0"):
        get_recipe("state", {"training.num_workers": -1})


def test_image_shifts_reach_lerobot_train_as_its_image_transforms(tmp_path):
    """``image_shift``: LeRobot's own image transforms, one random shift per image, and a run folder of its own."""
    import draccus
    import torch
    from lerobot.configs.default import DatasetConfig
    from lerobot.transforms.transforms import ImageTransforms

    from colorsort.training.pipeline_stages import train_command

    shifted = get_recipe("camera")
    args = shifted.training.augment_args()
    assert shifted.training.image_shift == 0.1
    assert get_recipe("camera", {"training.image_shift": 0}).training.augment_args() == []
    assert set(args) <= set(train_command(shifted, tmp_path, 10, 1000, tmp_path / "run"))
    config = draccus.parse(DatasetConfig, args=["--repo_id=local/x", *[a.replace("--dataset.", "--") for a in args]])
    transforms = ImageTransforms(config.image_transforms)
    image = torch.zeros(3, 32, 32)
    image[:, 12:20, 12:20] = 1.0
    moved = [transforms(image) for _ in range(20)]
    assert all(m.shape == image.shape and m.sum() == image.sum() for m in moved)  # moved whole, no border reached
    offsets = {tuple(torch.nonzero(m[0])[0].tolist()) for m in moved}
    assert len(offsets) > 1 and all(abs(r - 12) <= 3 and abs(c - 12) <= 3 for r, c in offsets)  # 0.1 of 32 px
    for bad in ({"training.image_shift": 0.5}, {"training.image_shift": -0.1}, {"demos.cameras": ()}):
        with pytest.raises(ValueError, match="image_shift"):
            get_recipe("camera", bad)


def test_relit_training_images_vary_as_the_lighting_variant_but_keep_every_box_colour(tmp_path):
    """``image_relight``: LeRobot's ``ColorJitter`` and ``PlanckianJitter`` on every image beside the shift:
    darker and brighter, warmer and colder, and a red, green or blue box keeps its strongest channel."""
    import draccus
    import torch
    from lerobot.configs.default import DatasetConfig
    from lerobot.transforms.transforms import ImageTransforms

    from colorsort.training.pipeline_stages import train_command

    relit = colorsort_baseline.chosen_recipe(["--recipe", "camera", "--training.image_relight=true"])
    args = relit.training.augment_args()
    assert "--dataset.image_transforms.max_num_transforms=3" in args
    assert set(args) <= set(train_command(relit, tmp_path, 10, 1000, tmp_path / "run"))
    config = draccus.parse(DatasetConfig, args=["--repo_id=local/x", *[a.replace("--dataset.", "--") for a in args]])
    transforms = ImageTransforms(config.image_transforms)
    image = torch.full((3, 32, 32), 0.4)  # a grey belt around three saturated boxes
    for channel, (r, c) in enumerate(((4, 4), (4, 20), (20, 12))):
        image[:, r:r + 8, c:c + 8] = 0.1
        image[channel, r:r + 8, c:c + 8] = 0.6
    torch.manual_seed(0)
    relit_images = [transforms(image) for _ in range(40)]
    grey = torch.stack([m[:, 16, 8:24].mean(dim=1) for m in relit_images])  # belt that no 3 px shift moves off
    assert grey.sum(dim=1).min() < 0.8 * 1.2 < 1.2 * 1.2 < grey.sum(dim=1).max()  # dimmer and brighter than 1.2
    assert (grey[:, 0] > grey[:, 2] * 1.1).any() and (grey[:, 2] > grey[:, 0] * 1.1).any()  # warm and cold
    for m in relit_images:
        for channel, (r, c) in enumerate(((4, 4), (4, 20), (20, 12))):
            box = m[:, r + 3:r + 5, c + 3:c + 5].mean(dim=(1, 2))  # the middle of the box, inside any shift
            assert int(box.argmax()) == channel
    with pytest.raises(ValueError, match="image_relight"):
        get_recipe("state", {"training.image_relight": True})


def test_bad_settings_name_the_valid_choices(tmp_path, capsys):
    from colorsort.cli.baseline import main

    for argv, named in ((["--recipe", "nope"], "Valid recipes"),
                        (["--demos.train_mix=default:1,nope:1"], "Valid variants"),
                        (["--demos.counts=50,20"], "increasing"),
                        (["--demos.cameras=top"], "Valid cameras"),
                        (["--demos.train_mix=default:x"], "not a valid float"),
                        (["--training.image_relight=maybe"], "true or false"),
                        (["--training.device=tpu"], "valid devices")):
        assert main([*argv, "--out", str(tmp_path)]) == 2, argv
        assert named in capsys.readouterr().err, argv
    assert exit_status(main, ["--until", "later"]) == 2


def test_baseline_help_shows_a_flag_for_every_recipe_field_and_perturbation(monkeypatch, tmp_path):
    """``colorsort-baseline --help``: the nested fields of the command's configuration (each with its comment and the
    chosen recipe's value), ``--policy.type``'s kinds and the perturbation registry's flags; ``Recipe.override``
    refuses an unknown key."""
    from dataclasses import fields

    from colorsort.data.perturbations import PERTURBATIONS

    monkeypatch.setenv("COLUMNS", "1000")  # one line per flag
    done = console_script("colorsort-baseline", ["--recipe", "camera-snapshot", "--help"], tmp_path)
    assert done.returncode == 0, done.stderr
    help_text = done.stdout
    recipe = get_recipe("camera-snapshot")
    for section in ("demos", "policy", "training", "dagger", "evaluation"):
        for f in fields(getattr(recipe, section)):
            if f.init:
                assert f"--{section}.{f.name}" in help_text, (section, f.name)
    assert all(f"--demos.{name}" in help_text for name in PERTURBATIONS)
    assert "--policy.type {act,diffusion}" in help_text and "--config_path" in help_text
    flat = " ".join(help_text.split())
    assert "--training.steps int training updates of the largest demo set. (default: 4000)" in flat
    assert "(default: snapshot)" in flat
    assert '(default: ["brightness:0.45,0.75","late_pass:100","late_pick:10"])' in flat
    with pytest.raises(ValueError, match="Valid settings"):
        recipe.override({"training.stpes": 10})


def test_baseline_flags_old_and_new_spellings_and_a_config_file_give_one_recipe(tmp_path):
    """The comma spelling the docs show, draccus's YAML spelling and ``--config_path`` parse to the same recipe; a
    perturbation's own flag changes it alone; ``--policy.type`` swaps the kind, with that kind's defaults."""
    from colorsort.cli.baseline import parse_args
    from colorsort.data.perturbations.late_pick import LatePick

    old = parse_args(["--recipe", "camera-snapshot", "--demos.counts=8,40", "--training.seeds", "1000,1002",
                      "--demos.late_pick=30", "--demos.train_mix=default:1,lighting:2", "--add-to", "x"])
    new = parse_args(["--recipe=camera-snapshot", "--demos.counts=[8,40]", "--training.seeds=[1000,1002]",
                      "--demos.perturbations=[\"brightness:0.45,0.75\",late_pass:100,late_pick:30]",
                      "--demos.train_mix=[[default,1],[lighting,2]]", "--add_to=x"])
    (tmp_path / "run.yaml").write_text("recipe: camera-snapshot\nadd_to: x\ndemos:\n  counts: [8, 40]\n"
                                       "  train_mix: [[default, 1], [lighting, 2]]\n"
                                       "  perturbations: ['brightness:0.45,0.75', 'late_pass:100', 'late_pick:30']\n"
                                       "training:\n  seeds: [1000, 1002]\n")
    from_file = parse_args(["--config_path", str(tmp_path / "run.yaml")])  # the file's recipe is the preset
    assert old == new == from_file
    assert old.demos.perturbations[-1] == LatePick(30) and old.add_to == "x"
    assert old.chosen() == get_recipe("camera-snapshot", {"demos.counts": (8, 40), "training.seeds": (1000, 1002),
                                                          "demos.late_pick": LatePick(30),
                                                          "demos.train_mix": (("default", 1.0), ("lighting", 2.0))})
    swapped = parse_args(["--recipe", "camera", "--policy.type=diffusion", "--policy.down_dims=32,64"]).chosen()
    assert swapped.policy.type == "diffusion" and swapped.policy.down_dims == (32, 64)
    assert swapped.policy.horizon == 16 and swapped.demos == get_recipe("camera").demos


def test_a_recipe_is_stored_with_its_results_as_json_in_its_sections():
    stored = get_recipe("camera-snapshot").to_json()
    assert json.loads(json.dumps(stored)) == stored
    assert stored["demos"]["perturbations"] == {"brightness": [0.45, 0.75], "late_pass": 100, "late_pick": 10}
    assert stored["policy"]["type"] == "act" and stored["training"]["steps"] == 4000
    from colorsort.training.publishing.tables import method_label as label
    from colorsort.training.results_file import PipelineResults

    assert label(PipelineResults.from_json(scores([], stored))) == "ACT, snapshot"
    assert label(PipelineResults.from_json(scores([], {"cameras": ["sensor", "wrist"]}))) == "ACT, sensor+wrist"  # flat
    assert "dagger" not in stored  # a recipe without DAgger's rounds is stored as before they were a setting


def test_dagger_rounds_are_recipe_settings_that_name_the_method_and_check_themselves():
    from colorsort.cli.baseline import parse_args
    from colorsort.training.publishing.tables import method_label as label
    from colorsort.training.results_file import PipelineResults

    recipe = get_recipe("state", {"dagger.rounds": 2, "dagger.episodes": 4, "dagger.handover": (10, 50)})
    assert recipe.label == "ACT + DAgger (2 rounds), state"
    stored = recipe.to_json()
    assert stored["dagger"] == {"rounds": 2, "episodes": 4, "handover": [10, 50], "rollout": "last",
                                "retrain": "scratch", "updates": 0, "variants": []}
    assert label(PipelineResults.from_json(scores([], stored))) == "ACT + DAgger (2 rounds), state"
    for text in ("10:50", "10,50", "[10,50]"):  # a pair as a list of pairs spells it, as --help shows it, as YAML
        assert parse_args(["--dagger.handover", text]).dagger.handover == (10, 50)
    for change, named in (({"dagger.rounds": -1}, "rounds=-1"), ({"dagger.episodes": 0}, "episodes=0"),
                          ({"dagger.handover": (50, 10)}, "FIRST:LAST")):
        with pytest.raises(ValueError, match=named):
            get_recipe("state", change)
    args = parse_args(["--recipe", "camera-tracking", "--dagger.variants=tracking-jitter"])
    assert args.dagger.variants == ("tracking-jitter",)
    with pytest.raises(ValueError, match=r"\['fast'\].*\['tracking', 'tracking-jitter'\]"):
        get_recipe("camera-tracking", {"dagger.rounds": 1, "dagger.variants": ("fast",)})
    from colorsort.training.publishing.ship import dagger_line

    assert "the last policy played 4 episodes of every training variant" in dagger_line(recipe, 100)
    assert "a new policy was trained from scratch" in dagger_line(recipe, 100)
    told = dagger_line(get_recipe("camera-tracking", {"dagger.rounds": 1, "dagger.variants": ("tracking-jitter",),
                                                       "dagger.rollout": "chosen", "dagger.retrain": "finetune"}), 100)
    assert "checkpoint chosen on validation seeds played 10 episodes of `tracking-jitter`," in told
    assert "the policy that played was trained further" in told


def test_averaged_checkpoints_name_the_method_and_leave_its_inputs_apart():
    from colorsort.training.method_names import method_name
    from colorsort.training.publishing.tables import method_label as label
    from colorsort.training.results_file import PipelineResults

    recipe = get_recipe("camera-tracking", {"training.average": 2})
    assert recipe.label == "ACT (mean of 2 checkpoints), sensor+snapshot+wrist"
    assert label(PipelineResults.from_json(scores([], recipe.to_json()))) == recipe.label
    method, _, inputs = recipe.label.partition(", ")  # how the methods table splits a label
    assert (method, inputs) == ("ACT (mean of 2 checkpoints)", "sensor+snapshot+wrist")
    assert method_name("act", 1, "finetune", 3) == "ACT (mean of 3 checkpoints) + DAgger (1 round, fine-tuned)"
    assert get_recipe("camera-diffusion").label.startswith("Diffusion Policy, ")


def test_recipes_split_demos_by_weight_and_never_give_a_camera_policy_the_box_state():
    assert get_recipe("state").demos.split(40) == {"default": 8, "jitter": 8, "fast": 8, "distractors": 16}
    camera = get_recipe("camera")
    assert camera.demos.split(48) == {"default": 8, "lighting": 8, "jitter": 8, "fast": 8, "distractors": 16}
    one_box_seed = get_recipe("camera", {"demos.train_mix": camera.demos.train_mix + (("seed", 1),),
                                         "demos.boxes_by_variant": (("seed", 1),)})
    assert (one_box_seed.demos.boxes("seed"), one_box_seed.demos.boxes("jitter")) == (1, camera.demos.boxes_per_episode)
    assert sum(camera.demos.split(7).values()) == 7
    training = camera.training
    assert (training.updates(True, 1000), training.updates(False, 1000)) == (training.steps, training.small_steps)
    with pytest.raises(ValueError, match="at least 1 box"):
        get_recipe("camera", {"demos.boxes_by_variant": (("seed", 0),)})
    with pytest.raises(ValueError, match="Valid variants"):
        get_recipe("camera", {"demos.boxes_by_variant": (("nope", 1),)})
    alike = get_recipe("state", {"demos.counts": (8, 40), "training.passes": 10.0, "training.batch_size": 64})
    assert (alike.training.updates(False, 2560), alike.training.updates(True, 12800)) == (400, 2000)
    with pytest.raises(ValueError, match="seeds"):
        get_recipe("state", {"training.seeds": (1, 1)})
    with pytest.raises(ValueError, match="passes"):
        get_recipe("state", {"training.passes": 0.0})
    for recipe in RECIPES.values():
        assert recipe.evaluation.main_variant in recipe.evaluation.variants
    tracking = get_recipe("camera-tracking")
    assert set(tracking.evaluation.variants) == {"tracking", "tracking-jitter", "tracking-fast"}
    assert tracking.demos.cameras


@pytest.mark.slow
def test_documented_recipe_list_runs_verbatim():
    """docs/baselines.md's `colorsort-baseline --list`, as written: one line per recipe."""
    page = (REPO / "docs" / "baselines.md").read_text()
    assert "colorsort-baseline --list\n" in page
    result = run(baseline("--list"), REPO, timeout=120)
    assert result.returncode == 0, result.stderr
    assert [line.split()[0] for line in result.stdout.splitlines()] == list(RECIPES)


def test_docs_tables_are_the_ones_scores_json_gives():
    """Every scores block in README and docs/ is what `python tools/baseline_tables.py` writes from its JSON;
    every shipped baseline with scores.json has its table in the docs."""
    from colorsort.training.publishing.tables import fill_baseline_tables as fill
    from colorsort.training.publishing.tables import pages

    text = {page: page.read_text() for page in pages(REPO)}
    for page, body in text.items():
        assert fill(body, REPO, page) == body, f"{page} is stale: run python tools/baseline_tables.py"
    for name, path in SHIPPED.items():
        if (path / "scores.json").is_file():
            assert any(f"<!-- scores baselines/{name} table -->" in t for t in text.values()), name


def test_training_times_over_seeds_read_as_one_figure_when_they_round_alike():
    from colorsort.training.publishing.run_summary import span

    assert span([53.6, 53.9, 54.2]) == "54"
    assert span([49.2, 57.4]) == "49-57"
    assert span([42.0]) == "42"


def test_a_stale_scores_block_is_rewritten_and_a_bad_one_refused():
    from colorsort.training.publishing.tables import fill_baseline_tables as fill

    stale = "before\n<!-- scores baselines/act-camera curve -->\n| old | numbers |\n<!-- end scores -->\nafter\n"
    new = fill(stale, REPO)
    assert "| old |" not in new and "| updates | training [min] |" in new
    assert new.startswith("before\n") and new.endswith("<!-- end scores -->\nafter\n") and fill(new, REPO) == new
    with pytest.raises(ValueError, match="Valid kinds"):
        fill("<!-- scores baselines/act-camera plot -->\n<!-- end scores -->", REPO)
    with pytest.raises(ValueError, match="no scores.json"):
        fill("<!-- scores baselines/nothing table -->\n<!-- end scores -->", REPO)


def test_the_headline_gives_a_baseline_of_several_seeds_its_mean_and_range(tmp_path):
    """One seed: the rate with its Wilson interval; three seeds: their mean and range, never one cell per seed."""
    from colorsort.training.publishing.tables import baselines_headline as headline

    def row(variant: str, seed: int, rate: float) -> dict:
        return score_row(variant=variant, seed=seed, success_rate=rate, success_ci95=[rate - 0.1, rate + 0.05])

    for name, rows in (("one", [row("default", 1000, 0.9)]),
                       ("three", [row(v, s, r) for s, r in ((1000, 0.9), (1001, 0.6), (1002, 0.75))
                                  for v in ("default", "fast")])):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scores.json").write_text(json.dumps(scores(rows)))
    point = {"episodes": 10, "successes": 5, "correct": 15, "misplaced": 0, "dropped": 0}
    chosen = [{**row("default", s, 1.0), "checkpoint": c,
               "validation": [{"step": 2500, "minutes": 10.0, **point}, {"step": 5000, "minutes": 20.0, **point}]}
              for s, c in ((1000, 5000), (1001, 2500))]
    (tmp_path / "two").mkdir()
    (tmp_path / "two" / "scores.json").write_text(json.dumps(scores(chosen)))
    one, three, two = headline(tmp_path).splitlines()[2:]
    assert "`default` 90% (80-95%, 50)" in one and "20 min on the CPU |" in one
    assert "`default` mean 75%, seeds 60-90% (3 x 50); `fast` mean 75%" in three
    assert "per seed, 3 seeds" in three and three.count("`default`") == 1
    # each run scored at the checkpoint its validation seeds chose: the training time is that checkpoint's
    assert "5000 updates, scored at 5000/2500 (chosen on validation seeds), 10-20 min on the CPU per seed" in two


def test_the_mistakes_table_counts_each_wrong_bin_by_colour_over_every_seed():
    """Two seeds' misplaced boxes add up per (colour, bin); correct and dropped boxes and smaller demo counts do not."""
    from colorsort.training.publishing.tables import render
    from colorsort.training.results_file import PipelineResults

    def row(seed: int, demos: int, boxes: list[tuple[str, str, str | None]]) -> dict:
        episode = {"boxes": [{"color": c, "outcome": o, "bin": b} for c, o, b in boxes]}
        return score_row(demos_tried=demos, variant="jitter", seed=seed, per_episode=[episode])

    rows = [row(1000, 48, [("red", "misplaced", "green"), ("blue", "correct", "blue"), ("red", "dropped", None)]),
            row(1001, 48, [("red", "misplaced", "green"), ("blue", "misplaced", "green")]),
            row(1000, 8, [("green", "misplaced", "red")])]
    table = render(PipelineResults.from_json(scores(rows)), "mistakes")
    assert table.splitlines()[2] == "| jitter | 3 | red -> green 2, blue -> green 1 |"
    clean = [row(1000, 48, [("red", "correct", "red")])]
    assert render(PipelineResults.from_json(scores(clean)), "mistakes").endswith("| every variant | 0 | |")


def test_a_shipped_readme_says_how_the_demos_were_made():
    """The README's demo line gives each variant's count, with the perturbations that act on some variants only
    after them, and those on every variant once at the end, each as it describes itself."""
    from colorsort.training.publishing.ship import demo_line

    assert demo_line(get_recipe("camera-snapshot")) == (
        "8 on default, 8 on lighting under lights of brightness x0.45-0.75, 8 on jitter, 8 on fast, 16 on "
        "distractors; 3 boxes each; every belt pass held back 0-100 steps; every pick held back 0-10 steps")
    assert demo_line(get_recipe("state", {"demos.late_pass": LatePass(0), "demos.late_pick": LatePick(5)})) == (
        "8 on default, 8 on jitter, 8 on fast, 16 on distractors; 3 boxes each; every pick held back 0-5 steps")
    assert demo_line(get_recipe("camera-tracking")) == "24 on tracking, 24 on tracking-jitter; 5 boxes each"
    deeper = get_recipe("camera-tracking", {"demos.expert": (("press", 0.01), ("track_hold_time", 0.15))})
    assert demo_line(deeper).endswith("; the expert's press 0.01, track_hold_time 0.15 (`ExpertConfig`, changed "
                                      "from its preset)")


def test_demos_without_the_wrists_turn_get_daggers_labels_without_it(tmp_path, monkeypatch):
    """``--demos.turn_to_box=false`` reaches colorsort-collect and colorsort-takeover alike as ``--no-turn``, so the
    labels come from the expert that made the demos."""
    from colorsort.training import pipeline_stages as stages
    from colorsort.training.pipeline_stages import collect_command, label

    still = colorsort_baseline.chosen_recipe(["--recipe", "camera", "--demos.turn_to_box=false"])
    turning = get_recipe("camera")
    assert "--no-turn" in collect_command(still, "jitter", 0, 8, 2)
    ran: list[list[str]] = []
    monkeypatch.setattr(stages, "run", lambda command, log: ran.append(command))  # what it would run, not a run
    model = tmp_path / "train" / "run" / "checkpoints" / "last" / "pretrained_model"
    assert label(still, model, "jitter", 0, 1, tmp_path) != label(turning, model, "jitter", 0, 1, tmp_path)
    assert "--no-turn" in ran[0] and "--no-turn" not in ran[1]


def test_the_experts_changed_settings_reach_the_demos_and_daggers_labels_and_key_their_caches(tmp_path, monkeypatch):
    """``--demos.expert`` reaches colorsort-collect of every training variant and colorsort-takeover, as their
    ``--expert``, so the demos and the labels come from one expert and no cache of the preset's is reused; an
    unknown setting or a value out of range is refused with the valid choices."""
    from colorsort.training import pipeline_stages as stages
    from colorsort.training.pipeline_stages import collect_command, collect_config, label, part_settings

    recipe = colorsort_baseline.chosen_recipe(
        ["--recipe", "camera-tracking", "--demos.expert=press:0.01,track_hold_time:0.15"])
    assert recipe.demos.expert == (("press", 0.01), ("track_hold_time", 0.15))
    preset = get_recipe("camera-tracking")
    for k, variant in enumerate(recipe.demos.train_variants):
        command = collect_command(recipe, variant, k, 24, 2)
        assert "--expert=press:0.01,track_hold_time:0.15" in command
        assert (part_settings(collect_config(recipe, variant, k, 24, 2))
                != part_settings(collect_config(preset, variant, k, 24, 2)))
        assert not any(a.startswith("--expert") for a in collect_command(preset, variant, k, 24, 2))
    ran: list[list[str]] = []
    monkeypatch.setattr(stages, "run", lambda command, log: ran.append(command))  # what it would run, not a run
    model = tmp_path / "train" / "run" / "checkpoints" / "last" / "pretrained_model"
    labels = [label(r, model, "tracking-jitter", 1, 1, tmp_path) for r in (recipe, preset)]
    assert labels[0] != labels[1]
    assert "--expert=press:0.01,track_hold_time:0.15" in ran[0]
    assert not any(a.startswith("--expert") for a in ran[1])  # the preset's labels keep the key they had
    with pytest.raises(ValueError, match="track_hold_time"):
        colorsort_baseline.chosen_recipe(["--recipe", "camera-tracking", "--demos.expert=hold:0.15"])
    with pytest.raises(ValueError, match=r"press=0.5 is out of range"):
        colorsort_baseline.chosen_recipe(["--recipe", "camera-tracking", "--demos.expert=press:0.5"])


def test_every_recipes_policy_arguments_are_ones_lerobot_accepts():
    """Each recipe's ``--policy.*`` arguments parse into LeRobot's own policy configuration (ACT's or diffusion's),
    whose checks run as lerobot-train's would: the diffusion recipe's GroupNorm, keypoints and crop among them; a
    misspelt argument is refused. (Training one: ``test_lerobot_cli``'s diffusion test, ``test_pipeline``'s ACT.)"""
    import draccus
    from lerobot.policies.act.configuration_act import ACTConfig
    from lerobot.policies.diffusion.configuration_diffusion import DiffusionConfig

    kinds = {"act": ACTConfig, "diffusion": DiffusionConfig}
    for recipe in RECIPES.values():
        args = [a.replace("--policy.", "--", 1) for a in recipe.policy.args(recipe.demos.image_size)
                if a.startswith("--policy.")]
        config = draccus.parse(kinds[recipe.policy.type], args=args)
        assert config.n_action_steps == recipe.policy.n_action_steps, recipe.name
        if recipe.policy.type == "diffusion":
            side = round(0.9 * recipe.demos.image_size)  # 90% of each side: 58 of 64 px, 29 of 32
            assert (config.use_group_norm, config.crop_shape, config.pretrained_backbone_weights) == (
                True, (side, side), None)
    with pytest.raises(SystemExit):
        draccus.parse(DiffusionConfig, args=["--crop_shapes=[58,58]"])


def test_the_headline_compares_methods_with_their_size_and_where_they_trained(tmp_path):
    """The method's name from the recipe's policy type, the weights counted from model.safetensors' header (as
    torch counts them), the machine from the recipe's device, each README linked from the page that shows it."""
    from safetensors.torch import load_file

    from colorsort.training.publishing.tables import baselines_headline as headline
    from colorsort.training.publishing.tables import parameters

    weights = load_file(SHIPPED["act-state"] / "model.safetensors")
    assert parameters(SHIPPED["act-state"]) == sum(t.numel() for t in weights.values())
    assert parameters(tmp_path) is None
    recipe = {"demos": {"cameras": ["snapshot"]}, "policy": {"type": "diffusion"}, "training": {"device": "cuda"}}
    (tmp_path / "baselines" / "dp").mkdir(parents=True)
    (tmp_path / "baselines" / "dp" / "scores.json").write_text(json.dumps(scores([score_row()], recipe)))
    (line,) = headline(tmp_path / "baselines", tmp_path / "docs").splitlines()[2:]
    assert line.startswith("| [`dp`](../baselines/dp/README.md) | Diffusion Policy | snapshot | - | ")
    assert "20 min on a GPU |" in line
    row = headline(REPO / "baselines").splitlines()[2:]
    assert any(r.startswith("| [`act-state`](baselines/act-state/README.md) | ACT | state | 0.7 M |") for r in row)
    # demos from an expert changed from its preset say how, as colorsort-baseline's --demos.expert takes it
    recipe["demos"]["expert"] = [["press", 0.01], ["track_hold_time", 0.15]]
    (tmp_path / "baselines" / "dp" / "scores.json").write_text(json.dumps(scores([score_row()], recipe)))
    (line,) = headline(tmp_path / "baselines", tmp_path / "docs").splitlines()[2:]
    assert " demos (expert `press:0.01,track_hold_time:0.15`), " in line


def test_the_pipeline_runs_its_evaluations_and_labels_from_typed_configs_that_parse_back():
    """The evaluation and label stages build ``colorsort-eval``'s and ``colorsort-takeover``'s typed configurations,
    run the flags those write (which parse back into the same configuration) and key their caches on the
    configuration's settings: where the episodes run is no part of a key, every setting that changes them is."""
    from dataclasses import replace
    from pathlib import Path

    from colorsort.cli.eval import parse_args as eval_args
    from colorsort.cli.takeover import parse_args as takeover_args
    from colorsort.training import pipeline_stages as stages

    touch = get_recipe("camera-snapshot-touch-dr")
    dip = get_recipe("camera-tracking", {"demos.expert": (("press", 0.01), ("track_hold_time", 0.15)),
                                         "demos.turn_to_box": False, "evaluation.episode_length": 300})
    for recipe, variant, seed, shift in ((touch, "jitter", 20000, touch.evaluation.select_shift),
                                         (dip, "tracking", None, "")):
        config = replace(stages.eval_config(recipe, Path("run/pretrained_model"), variant, 10, 2, seed, shift),
                         json="out.json", resume=True)
        assert eval_args(config.argv()) == config
        again = stages.eval_config(recipe, Path("run/pretrained_model"), variant, 10, 8, seed, shift)
        assert again.settings() == config.settings()  # 8 envs or 2: the same episodes
        assert stages.eval_config(recipe, Path("m"), variant, 11, 2, seed, shift).settings() != config.settings()
    model = Path("out/train/run/checkpoints/001000/pretrained_model")
    label = replace(stages.label_config(dip, model, "tracking-jitter", 1, 2), out="labels")
    assert takeover_args(label.argv()) == label and not label.turn_to_box and label.expert == dip.demos.expert
