"""The documentation: README as a landing page, every link resolving inside the repository, its commands run.

The commands the docs pages show are run verbatim by the tests of their concepts (``test_lerobot_cli``,
``test_scale``, ``test_baseline``); README's own code blocks are either run here or are copies of
a docs page's block, so every command a user reads is one a test ran.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from helpers import python_script

REPO = Path(__file__).resolve().parents[1]
README = REPO / "README.md"
PAGES = [README, *sorted((REPO / "docs").rglob("*.md")), *sorted((REPO / "baselines").glob("*/README.md")),
         *sorted((REPO / "colorsort" / "assets").glob("*/README.md"))]
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)


def slug(heading: str) -> str:
    """GitHub's anchor for a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    text = FENCE.sub("", page.read_text())
    return {slug(line.lstrip("#")) for line in text.splitlines() if line.startswith("#")}


def test_readme_is_a_landing_page():
    lines = README.read_text().splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines: move guides to docs/"
    for page in ("task", "expert", "tracking", "data", "scaling", "benchmark", "shifts", "baselines", "speed",
                 "architecture", "stack"):
        assert f"(docs/{page}.md)" in README.read_text(), f"README's map of the docs misses docs/{page}.md"


REFERENCE_LINES = 300  # a reference page; run logs, single runs' timings and diagnoses go to docs/studies/


@pytest.mark.parametrize("page", sorted((REPO / "docs").glob("*.md")), ids=lambda p: p.name)
def test_a_reference_page_stays_a_reference(page):
    lines = len(page.read_text().splitlines())
    assert lines <= REFERENCE_LINES, f"docs/{page.name} has {lines} lines: move run logs and diagnoses to docs/studies/"


def map_section(lines: list[str], folder: str) -> str:
    """The lines of docs/architecture.md's map under ``folder`` (``colorsort/cell``): its line and every deeper one."""
    for part in folder.split("/"):
        start = next(i for i, line in enumerate(lines) if line.lstrip().startswith(part + "/"))
        indent = len(lines[start]) - len(lines[start].lstrip())
        end = next((i for i in range(start + 1, len(lines)) if lines[i].strip()
                    and len(lines[i]) - len(lines[i].lstrip()) <= indent), len(lines))
        lines = lines[start:end]
    return "\n".join(lines)


def test_the_architecture_map_lists_every_module_and_every_shipped_baseline():
    page = (REPO / "docs" / "architecture.md").read_text()
    tree = page.split("```")[1].splitlines()
    package = REPO / "colorsort"
    missing = [str(f.relative_to(package)) for f in sorted(package.rglob("*.py")) if f.name != "__init__.py"
               and not re.search(rf"(?<![\w/]){re.escape(f.name)}",
                                 map_section(tree, "/".join(("colorsort", *f.relative_to(package).parts[:-1]))))]
    assert not missing, f"docs/architecture.md's map misses {missing}"
    shipped = [d.name for d in sorted((REPO / "baselines").iterdir()) if (d / "README.md").is_file()]
    baselines = map_section(tree, "baselines")
    assert not [b for b in shipped if f"{b}/" not in baselines], "the map misses a shipped baseline"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(REPO)))
def test_every_link_resolves_inside_the_repository(page):
    for target in LINK.findall(FENCE.sub("", page.read_text())):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        assert resolved.is_relative_to(REPO), f"{page.name}: {target} points outside the repository"
        assert resolved.exists(), f"{page.name}: {target} does not exist"
        if anchor and resolved.suffix == ".md":
            assert anchor in anchors(resolved), f"{page.name}: {target}: no heading with that anchor"


def test_nothing_points_outside_the_repository():
    """No file names notes that only the authors' machines had."""
    tracked = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True).stdout.split()
    if not tracked:
        pytest.skip("not a git checkout")
    outside = re.compile(r"\.\./shared|DESIGN\.md|STACK\.md")
    for name in tracked:
        path = REPO / name
        if path.suffix in (".py", ".md", ".toml", ".txt", ".ini", ".cfg", ".json") or name in ("Makefile",):
            text = path.read_text(errors="replace")
            assert not outside.search(text), f"{name} points outside the repository: {outside.search(text)[0]}"


def readme_blocks(language: str) -> list[str]:
    return [body for lang, body in FENCE.findall(README.read_text()) if lang == language]


def test_readmes_shell_blocks_are_the_docs_tested_ones_or_run_here():
    """A README command block is a copy of a docs page's block (whose test runs it) or the expert's
    command, which ``test_readmes_expert_command_runs_as_written`` runs."""
    docs = "\n".join(p.read_text() for p in sorted((REPO / "docs").glob("*.md")))
    for body in readme_blocks(""):
        assert body in docs or body.startswith("colorsort-sort "), f"README block not in the docs:\n{body}"


def test_readmes_python_snippet_runs(tmp_path):
    """The snippet run as a script in this process."""
    (snippet,) = readme_blocks("python")
    script = tmp_path / "snippet.py"
    script.write_text(snippet + "\nassert not done and reward >= 0\nenv.close()\n")
    result = python_script(script, [], tmp_path)
    assert result.returncode == 0, (result.stdout + result.stderr)[-3000:]


@pytest.mark.slow
def test_readmes_expert_command_runs_as_written(tmp_path):
    (line,) = [b.strip() for b in readme_blocks("") if b.startswith("colorsort-sort ")]
    argv = shlex.split(line)
    result = subprocess.run([str(Path(sys.executable).parent / argv[0]), *argv[1:]], cwd=tmp_path,
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    import json

    report = json.loads((tmp_path / "outputs" / "sort.json").read_text())
    assert (tmp_path / "outputs" / "sort.mp4").stat().st_size > 10_000
    wanted = int(argv[argv.index("--boxes") + 1])
    assert report["correct"] == len(report["boxes"]) == wanted, report
    assert report["misplaced"] == report["dropped"] == 0 and all(b["bin"] == b["true_color"] for b in report["boxes"])


def test_a_benchmark_script_writes_what_it_printed_with_its_command_machine_and_date(tmp_path, monkeypatch, capsys):
    from colorsort.results import recorded

    monkeypatch.setenv("COLORSORT_RESULTS", str(tmp_path))
    with recorded("benchmarks/bench_example.py", ["--seeds", "3"]):
        print("measure   value\nsteps/s   1,234")
    (page,) = tmp_path.iterdir()
    assert page.name == "bench_example_seeds-3.md"
    text = page.read_text()
    assert text.startswith("# `python benchmarks/bench_example.py --seeds 3`\n")
    assert "cores" in text and " UTC " in text and "steps/s   1,234\n```" in text
    assert "steps/s   1,234" in capsys.readouterr().out  # printed as usual too
    monkeypatch.setenv("COLORSORT_RESULTS", "none")
    with recorded("benchmarks/bench_example.py", []):
        print("nothing kept")
    assert len(list(tmp_path.iterdir())) == 1


def test_every_results_file_the_docs_link_exists_and_every_results_file_is_linked():
    results = REPO / "docs" / "results"
    docs = "\n".join(p.read_text() for p in [README, *(REPO / "docs").glob("*.md")])
    for page in sorted(results.glob("*.md")) if results.is_dir() else []:
        assert f"results/{page.name}" in docs, f"docs/results/{page.name} is linked from no page"


def test_make_bench_rewrites_exactly_the_results_files_the_docs_link(monkeypatch):
    """Every docs/results file is what a line of `make bench` writes, and every such line's file is there."""
    from colorsort.results import results_path

    monkeypatch.delenv("COLORSORT_RESULTS")
    makefile = (REPO / "Makefile").read_text()
    recipe = makefile[makefile.index("\nbench:"):].split("\n\n")[0]
    commands = [shlex.split(line.split("$(VENV)/bin/python", 1)[1]) for line in recipe.splitlines()
                if "$(VENV)/bin/python benchmarks/" in line]
    expected = {results_path(argv[0], argv[1:]).name for argv in commands}
    present = {p.name for p in (REPO / "docs" / "results").glob("*.md")}
    assert expected == present, f"make bench writes {sorted(expected - present)}; unknown: {sorted(present - expected)}"


NAMED_PATH = re.compile(r"(?<![\w/.-])((?:docs|colorsort|benchmarks|tests|tools|demos|baselines|assets)/[\w./-]*\w)")
RETIRED = re.compile(r"git show \w+:\S+")  # a file as it was at a commit: named on purpose, gone since
ELSEWHERE = {"colorsort/assets": "the wheel's copy of assets/ (docs/install.md)"}


def named_paths(text: str) -> set[str]:
    """Repository paths a text names (``docs/shifts.md``, ``colorsort/envs/servo.py``); not placeholders
    (``baselines/NAME``), prefixes (``demos/probe_``), Gymnasium ids (``colorsort/ColorSort-v0``), globs or files
    named as they were at a commit."""
    found = set()
    text = RETIRED.sub("", text)
    for match in NAMED_PATH.finditer(text):
        if text[match.end():match.end() + 1] == "<":  # a pattern: baselines/NAME/seed<N>/
            continue
        name = match.group(1).partition("#")[0]
        parts = name.split("/")
        if ("*" in name or "<" in name or name.endswith("_") or parts[1].startswith("ColorSort")
                or any(p.isupper() for p in parts)):
            continue
        found.add(name)
    return found


def test_every_path_a_docstring_or_a_docs_page_names_exists():
    """A module, file or page named in a Python file's text (docstrings, comments) or a docs page is there: a
    description that names a moved or renamed file is caught. The studies are dated run logs that name files as
    they were then."""
    pages = [p for p in PAGES if "studies" not in p.parts]
    code = sorted(p for d in ("colorsort", "benchmarks", "tools", "demos") for p in (REPO / d).rglob("*.py"))
    sources = [*pages, *code]
    missing = {}
    for source in sources:
        for name in named_paths(source.read_text()):
            if name in ELSEWHERE:
                continue
            if not any(p.exists() for p in (REPO / name, REPO / "colorsort" / name, source.parent / name)):
                missing.setdefault(name, str(source.relative_to(REPO)))
    assert not missing, f"named but not in the repository (path: where it is named): {missing}"
