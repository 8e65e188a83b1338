"""colorsort-eval --report: filmed episodes, the report page, and the page in a real browser (Chromium)."""

import json
import re
import shlex
import shutil
import subprocess
from dataclasses import asdict
from pathlib import Path

import pytest
from helpers import console_script

from colorsort.benchmark.episode_result import EpisodeResult
from colorsort.benchmark.evaluate import run_evaluation
from colorsort.benchmark.metrics import aggregate
from colorsort.benchmark.report_page import SUCCESSES_FILMED, choose_films
from colorsort.data.video import read_video

ROOT = Path(__file__).resolve().parents[1]
STATE_POLICY = ROOT / "baselines" / "act-state"
SHORT = ["--episodes", "2", "--episode-length", "120"]  # in place of the documented 10 full episodes


def documented_report_command() -> list[str]:
    """The ``--report`` command docs/benchmark.md shows."""
    text = (ROOT / "docs" / "benchmark.md").read_text()
    (line,) = [ln for ln in text.splitlines() if ln.startswith("colorsort-eval ") and "--report outputs/" in ln]
    return shlex.split(line)


def short(argv: list[str], out: Path) -> list[str]:
    """The documented command's arguments on 2 short episodes, writing its report to ``out``."""
    args = argv[1:]
    args[args.index("--episodes"):args.index("--episodes") + 2] = SHORT
    args[args.index("--report") + 1] = str(out)
    return args


def eval_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return console_script("colorsort-eval", list(args), cwd)


@pytest.mark.slow
@pytest.mark.parametrize("policy", ["expert", str(STATE_POLICY)], ids=["expert", "state-policy"])
def test_filming_changes_no_result_and_films_every_step(policy, tmp_path):
    kwargs = dict(episodes=2, cameras=(), image_size=(64, 64), progress=False, episode_length=60)
    if policy == "expert":
        kwargs["cameras"] = ("scene", "wrist")
    plain = run_evaluation(policy, ["default"], **kwargs)
    filmed = run_evaluation(policy, ["default"], film=True, **kwargs)
    assert [asdict(r) for r in plain.reports] == [asdict(r) for r in filmed.reports]
    assert not plain.films and sorted(filmed.films) == [("default", 10000), ("default", 10001)]
    episode = filmed.reports[0].per_episode[0]
    path = tmp_path / "film.mp4"
    path.write_bytes(filmed.films[("default", 10000)])
    frames = read_video(path)
    assert frames.shape == (episode["steps"] + 1, 360, 480, 3)  # the reset and every step
    assert frames[-1].std() > 10  # a picture, not a blank frame


def test_the_report_keeps_every_failure_first_and_a_few_successes():
    results = [EpisodeResult(seed=s, success=s % 3 == 0, ended="x", steps=1, correct=0, misplaced=0, dropped=0,
                             let_through=0, distractors=0, sim_time=1.0, sorted_times=[], boxes=[]) for s in range(10)]
    report = aggregate("p", "default", results)
    films = {("default", s): bytes([s]) for s in range(10)}
    failures = [s for s in range(10) if s % 3]
    successes = [0, 3, 6, 9]
    assert list(choose_films([report], films, None)) == [("default", s) for s in failures +
                                                         successes[:SUCCESSES_FILMED]]
    assert list(choose_films([report], films, 2)) == [("default", 1), ("default", 2)]
    assert choose_films([report], films, 0) == {}


def test_report_arguments_that_make_no_sense_are_refused_and_an_old_report_is_kept(tmp_path):
    old = tmp_path / "report"
    old.mkdir()
    (old / "index.html").write_text("an earlier report")
    done = eval_cli("--policy", "expert", "--episodes", "1", "--report", str(old), cwd=tmp_path)
    assert done.returncode == 2 and "--overwrite" in done.stderr
    assert (old / "index.html").read_text() == "an earlier report"
    done = eval_cli("--policy", "expert", "--episodes", "1", "--videos", "2", cwd=tmp_path)
    assert done.returncode == 2 and "--report" in done.stderr
    done = eval_cli("--policy", "expert", "--episodes", "1", "--report", str(tmp_path / "r"), "--videos", "-1",
                    cwd=tmp_path)
    assert done.returncode == 2 and "--videos -1" in done.stderr


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The documented report command on 2 short episodes (both time out: failures), with --json beside."""
    out = tmp_path_factory.mktemp("report") / "report"
    args = short(documented_report_command(), out) + ["--json", str(out.parent / "eval.json"), "--envs", "2"]
    done = console_script("colorsort-eval", args, ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    assert f"report: {out / 'index.html'} (2 videos)" in done.stdout
    return out


@pytest.mark.slow
def test_the_report_folder_holds_the_page_its_videos_and_the_json(report):
    assert json.loads((report / "report.json").read_text()) == json.loads((report.parent / "eval.json").read_text())
    page = (report / "index.html").read_text()
    assert "http://" not in page and "https://" not in page  # nothing fetched from the network
    assert sorted(p.name for p in (report / "videos").iterdir()) == ["distractors_seed10000.mp4",
                                                                    "distractors_seed10001.mp4"]
    assert (report / "outcomes.svg").read_text().lstrip().startswith("<?xml")
    assert page.count("<video") == 2 and "time limit" in page


def test_the_report_opens_from_disk_in_chromium_and_its_videos_play(report, tmp_path):
    browser_path = shutil.which("chromium") or shutil.which("chromium-browser")
    if browser_path is None:
        pytest.skip("headless Chromium not found: install Debian's chromium (apt-get install chromium) "
                    "to run the browser test")
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright comes with the dev extra: "
                                                                  "pip install -e '.[dev]'")
    results = json.loads((report / "report.json").read_text())
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=browser_path)
        try:
            page = browser.new_page(viewport={"width": 1200, "height": 1400})
            page.goto((report / "index.html").as_uri())
            rows = page.locator("#summary tr").all_inner_texts()
            assert len(rows) == 2 and rows[1].split()[0] == "distractors"
            videos = page.evaluate("""async () => Promise.all([...document.querySelectorAll('video')].map(
                async v => {
                    if (v.readyState < 1) await new Promise((ok, bad) => {
                        v.addEventListener('loadedmetadata', ok); v.addEventListener('error', bad); v.load(); });
                    await v.play();
                    while (v.currentTime < 0.3) await new Promise(ok => setTimeout(ok, 50));
                    v.pause();
                    return {src: v.getAttribute('src'), duration: v.duration, width: v.videoWidth,
                            height: v.videoHeight, played: v.currentTime, error: v.error && v.error.code};
                }))""")
            page.screenshot(path=str(tmp_path / "report.png"), full_page=True)
        finally:
            browser.close()
    assert len(videos) == 2
    for video, episode in zip(videos, results["per_episode"], strict=True):
        assert video["src"] == f"videos/distractors_seed{episode['seed']}.mp4"
        assert video["error"] is None and (video["width"], video["height"]) == (480, 360)
        assert video["duration"] == pytest.approx((episode["steps"] + 1) / 20, abs=0.06)
        assert video["played"] >= 0.3
    assert (tmp_path / "report.png").stat().st_size > 20_000
    assert re.match(rb"\x89PNG", (tmp_path / "report.png").read_bytes()[:4])
