"""The commands' configurations as their command lines (``colorsort.cli.config_args``, docs/commands.md): nested
fields with their help, ``--config_path``, and every spelling the docs have shown parsing to the same settings."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import console_script, exit_status

from colorsort.benchmark.eval_command import SweepConfig
from colorsort.cli import collect as collect_cli
from colorsort.cli import eval as eval_cli
from colorsort.data.perturbations.brightness import Brightness
from colorsort.data.perturbations.late_pass import LatePass
from colorsort.executors.base import ExecutorConfig


def help_of(command: str, cwd: Path) -> str:
    """``command --help``'s text (by the console script's entry point), joined into one line."""
    done = console_script(command, ["--help"], cwd)
    assert done.returncode == 0, done.stderr
    return " ".join(done.stdout.split())


@pytest.mark.parametrize(("command", "nested"), [
    ("colorsort-collect", ["--executor.workers int tasks run at once (local: processes; ray: tasks of 1 CPU each)",
                           "--executor.name str \"local\": processes on this machine; \"ray\": a Ray cluster"]),
    ("colorsort-eval", ["--report.dir [str] write a report page here", "--sweep.levels int,int,... the levels",
                        "--executor.workers int tasks run at once"]),
    ("colorsort-baseline", ["--training.steps int training updates of the largest demo set.",
                            "--policy.type {act,diffusion}", "--dagger.rounds int rounds after the first training"]),
])
def test_help_shows_the_nested_fields_with_their_help(command, nested, tmp_path):
    text = help_of(command, tmp_path)
    assert "--config_path str" in text
    for line in nested:
        assert line in text, line


def test_collect_reads_the_old_spellings_draccus_s_and_a_config_file_alike(tmp_path):
    old = collect_cli.parse_args(["--variant", "lighting", "--episodes", "8", "--boxes-per-episode", "3", "--cameras",
                                  "snapshot,wrist", "--image-size", "32", "--workers", "2", "--late-pass=100",
                                  "--brightness=0.45,0.75", "--no-turn", "--resume", "--expert", "press:0.01"])
    new = collect_cli.parse_args(["--variant=lighting", "--episodes=8", "--boxes_per_episode=3",
                                  "--cameras=[snapshot,wrist]", "--image_size=[32,32]", "--executor.workers=2",
                                  '--perturbations=["brightness:0.45,0.75",late_pass:100]', "--turn_to_box=false",
                                  "--resume=true", "--expert=[[press,0.01]]"])
    (tmp_path / "c.yaml").write_text("episodes: 8\nboxes_per_episode: 3\ncameras: [snapshot, wrist]\n"
                                     "image_size: [32, 32]\nexecutor:\n  workers: 2\nturn_to_box: false\n"
                                     "perturbations: ['brightness:0.45,0.75', 'late_pass:100']\n"
                                     "expert: [[press, 0.01]]\nresume: true\n")
    from_file = collect_cli.parse_args(["--variant", "lighting", "--config_path", str(tmp_path / "c.yaml")])
    assert old == new == from_file
    assert old.executor == ExecutorConfig(workers=2) and old.image_size == (32, 32) and not old.turn_to_box
    assert old.perturbations == (Brightness(0.45, 0.75), LatePass(100)) and old.expert == (("press", 0.01),)
    assert collect_cli.parse_args(["--cameras", "none", "--image-size", "96x128"]).cameras == ()


def test_eval_reads_the_old_spellings_and_draccus_s_alike():
    old = eval_cli.parse_args(["--policy", "expert", "--envs", "2", "--shift", "camera-pose:2", "--shift", "box-size:1",
                               "--report", "out/r", "--videos", "0", "--overwrite", "--episode-length", "20"])
    new = eval_cli.parse_args(["--policy=expert", "--executor.workers=2", "--shift=[camera-pose:2,box-size:1]",
                               "--report.dir=out/r", "--report.videos=0", "--report.overwrite=true",
                               "--episode_length=20"])
    assert old == new and old.shift == ("camera-pose:2", "box-size:1") and old.report.videos == 0
    swept = eval_cli.parse_args(["--sweep", "--sweep-shifts", "image-noise,action-delay", "--levels", "1,2",
                                 "--side-episodes", "1"])
    assert swept.sweep == SweepConfig(True, ("image-noise", "action-delay"), (1, 2), 1)
    assert eval_cli.parse_args(["--executor", "ray", "--address", "auto"]).executor == ExecutorConfig("ray", 1, 2,
                                                                                                      "auto")


@pytest.mark.parametrize(("argv", "named"), [
    (["--episodes", "0"], "--episodes 0: give at least 1"),
    (["--levels", "1,5", "--sweep"], "levels from [1, 2, 3]"),
    (["--overwrite=maybe"], "give true or false"),
    (["--backend", "tpu"], "valid backends are ['cpu', 'warp']"),
    (["--executor", "slurm"], "Valid executors: ['local', 'ray']"),
    (["--sweep", "--shift", "camera-pose:1"], "--sweep runs its own arms"),
    (["--no-such-flag", "1"], "unrecognized arguments"),
])
def test_a_bad_flag_or_value_exits_2_naming_what_is_valid(argv, named, capsys):
    assert exit_status(eval_cli.main, argv) == 2
    assert named in capsys.readouterr().err


def test_a_bad_collect_value_exits_2_naming_the_valid_ones(capsys, tmp_path):
    for argv, named in ((["--fps", "7"], "Valid values: [10, 20, 25, 50]"),
                        (["--variant", "fast", "--preset", "default"], "give --variant alone"),
                        (["--late-pass=x"], "late_pass"),
                        (["--cameras", "top"], "give distinct names from")):
        assert exit_status(collect_cli.main, [*argv, "--out", str(tmp_path / "d")]) == 2, argv
        assert named in capsys.readouterr().err, argv
    assert not (tmp_path / "d").exists()


def test_collect_shift_given_twice_combines_and_refuses_a_held_out_level_wherever_it_is(capsys):
    """colorsort-collect's --shift, repeated, combines as colorsort-eval's does: a held-out level given first is
    refused (exit 2, one line), never dropped in favour of the last flag."""
    assert collect_cli.parse_args(["--shift", "box-mass:train", "--shift", "image-noise:train"]).shift == \
        "box-mass:train,image-noise:train"
    assert collect_cli.main(["--shift", "camera-pose:2", "--shift", "image-noise:train", "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "camera-pose:2 randomises into held-out level 2" in err[0]


def test_usage_shows_list_values_comma_separated_as_the_flags_take_them(capsys):
    """--help's usage line writes a list field as the flags take it (commas), not draccus's space-separated form."""
    with pytest.raises(SystemExit):
        eval_cli.parse_args(["--help"])
    usage = capsys.readouterr().out
    assert "[--shift str,str,...]" in usage and "[--sweep.levels int,int,...]" in usage
    assert "[str, ...]" not in usage and "[int, ...]" not in usage
    assert eval_cli.parse_args(["--sweep", "--levels", "1,3"]).sweep.levels == (1, 3)


def test_the_command_line_parser_uses_only_public_draccus_and_argparse():
    """``cli/config_args.py`` subclasses nothing of draccus's or argparse's and reaches no ``_private`` name of
    theirs: the defaults travel as a config file under the flags, the help is the parser's ``format_help``."""
    import ast

    from colorsort.cli import config_args
    tree = ast.parse(Path(config_args.__file__).read_text())
    private = [ast.unparse(n) for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr.startswith("_")
               and not n.attr.startswith("__")]
    private += [f"{n.module}.{a.name}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and n.module
                for a in n.names if a.name.startswith("_") and n.module != "__future__"]
    subclassed = [ast.unparse(b) for n in ast.walk(tree) if isinstance(n, ast.ClassDef) for b in n.bases]
    assert private == [] and subclassed == []


def test_help_shows_the_recipes_defaults_and_no_group_config_files(tmp_path):
    """draccus's per-group config-file flags (``--report str``) are not shown: ``--report DIR`` means
    ``--report.dir`` here; the defaults shown are the chosen recipe's."""
    text = help_of("colorsort-eval", tmp_path)
    assert "Config file for" not in text and "[--report str]" not in text and "--report.dir [str]" in text
    done = console_script("colorsort-baseline", ["--recipe", "camera-snapshot-touch-dr", "--help"], tmp_path)
    shown = " ".join(done.stdout.split())
    assert done.returncode == 0 and "(default: 96)" in shown and "Config file for" not in shown
