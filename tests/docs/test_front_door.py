"""The front door stays true: the README, the docs, the examples, the scenes, the command line's help and the
package's messages use words a user knows, and name only files, commands, flags and scene keys that exist.

Internal words are those of the project's own development: numbered reference problems of a file that is not in the
repository, "the seed" for the method paper (Tzamtzis & Asteris), numbered issues, and in the user's pages the
sessions, helpers, review fixes, commit hashes and search corpora of a development log. Each check is first shown to
fail on a text that breaks it, so that a check that cannot fail is noticed.
"""
from __future__ import annotations

import argparse
import re
import shlex
from pathlib import Path

import pytest
from repository_paths import DOCS, EXAMPLES, REPOSITORY_ROOT

from masonrydam.cli.main import build_parser
from masonrydam.scene.reference import keys as scene_keys

README = REPOSITORY_ROOT / "README.md"
DOC_PAGES = sorted(DOCS.glob("*.md"))

#: words that are internal wherever a user can meet them: pages, examples, scenes, help, messages, docstrings
INTERNAL_WORDS = {
    "a numbered reference problem of a file not in the repository": r"\breference problems? \d",
    "the name of a file not in the repository": r"\bPROBLEMS\.md|\bshared/(?:reference|seed|design|records)\b",
    "'the seed' for the method paper (write Tzamtzis & Asteris)": r"\bthe seed\b(?!\s*(?:=|of the|for the|value))"
                                                                 r"|\bseed paper\b|\bseed's\b",
    "a numbered development issue": r"\bissues? #?\d+",
}

#: words of a development log, which a user's page (README, docs, examples, help) has no use for
LOG_WORDS = {
    "a development session": r"\bsessions?\b",
    "a development helper": r"\bhelpers?\b",
    "review fixes": r"\breview fix",
    "a search tool's corpora": r"\bcorp(?:us|ora)\b",
    "a commit hash": r"\b(?:main|commit|HEAD)\s+[0-9a-f]{7,40}\b",
    "a development stop": r"\bstop \d+\b",
}


def _user_pages() -> list[Path]:
    """README, docs, examples, bundled scenes and the records' catalog: what a user reads."""
    pages = [README, *DOC_PAGES, *sorted(p for p in EXAMPLES.iterdir() if p.is_file())]
    pages += sorted((REPOSITORY_ROOT / "masonrydam" / "scenes").glob("*.toml"))
    pages += sorted((REPOSITORY_ROOT / "records").glob("*.toml")) + sorted((REPOSITORY_ROOT / "records").glob("*.md"))
    return pages


def _package_sources() -> list[Path]:
    """The package and the generators: messages, result attributes, schema text and docstrings."""
    return sorted((REPOSITORY_ROOT / "masonrydam").rglob("*.py")) + sorted((REPOSITORY_ROOT / "generators").rglob("*.py"))


def _parsers() -> dict[str, argparse.ArgumentParser]:
    """Each command of the command line ('', 'run', 'records show', ...) and its parser."""
    parsers = {}

    def walk(parser, name):
        parsers[name] = parser
        for action in parser._actions:  # argparse keeps its sub-parsers here, without a public accessor
            if isinstance(action, argparse._SubParsersAction):
                for sub_name, sub in action.choices.items():
                    walk(sub, f"{name} {sub_name}".strip())

    walk(build_parser(), "")
    return parsers


def _help_texts() -> dict[str, str]:
    """The help of the command line and of each of its commands (and of `records list` / `records show`)."""
    return {f"masonrydam {name}".strip(): parser.format_help() for name, parser in _parsers().items()}


def _marker_texts() -> str:
    """The pytest markers' descriptions, which ``pytest --markers`` prints."""
    import tomllib

    return "\n".join(tomllib.loads((REPOSITORY_ROOT / "pyproject.toml").read_text())["tool"]["pytest"]["ini_options"]
                     ["markers"])


def find_words(text: str, words: dict[str, str]) -> list[str]:
    """Each match of ``words`` (description -> regular expression, case-insensitive) in ``text``, with its line."""
    found = []
    for number, line in enumerate(text.splitlines(), 1):
        for what, pattern in words.items():
            for match in re.finditer(pattern, line, flags=re.IGNORECASE):
                found.append(f"line {number}: {match.group(0)!r} ({what}): {line.strip()[:140]}")
    return found


def test_the_words_check_finds_what_it_is_for():
    text = ("As reference problem 5 (PROBLEMS.md) shows, the seed's law (issue 17) holds.\n"
            "A helper measured it in session 3 (main fc33963), stop 48.")
    assert len(find_words(text, INTERNAL_WORDS)) == 4
    assert len(find_words(text, LOG_WORDS)) == 4
    assert find_words("set the seed = 3 for the sampling; Tzamtzis & Asteris sec. 3.4", INTERNAL_WORDS) == []


@pytest.mark.parametrize("path", _user_pages() + _package_sources(), ids=lambda p: str(p.relative_to(REPOSITORY_ROOT)))
def test_no_internal_words(path):
    found = find_words(path.read_text(encoding="utf-8"), INTERNAL_WORDS)
    assert not found, f"{path.relative_to(REPOSITORY_ROOT)}:\n" + "\n".join(found)


@pytest.mark.parametrize("path", _user_pages(), ids=lambda p: str(p.relative_to(REPOSITORY_ROOT)))
def test_no_development_log_in_user_pages(path):
    found = find_words(path.read_text(encoding="utf-8"), LOG_WORDS)
    assert not found, f"{path.relative_to(REPOSITORY_ROOT)}:\n" + "\n".join(found)


def test_no_internal_words_in_help_and_markers():
    found = []
    for name, text in {**_help_texts(), "pytest markers": _marker_texts()}.items():
        found += [f"{name}: {f}" for f in find_words(text, {**INTERNAL_WORDS, **LOG_WORDS})]
    assert not found, "\n".join(found)


# -- what the pages name exists -----------------------------------------------------------------------------------
CODE_SPAN = re.compile(r"`([^`\n]+)`")
FENCE = re.compile(r"^```[^\n]*\n(.*?)^```", re.MULTILINE | re.DOTALL)
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
REPOSITORY_PATH = re.compile(r"^(?:examples|docs|benchmarks|tests|masonrydam|generators|records)/[\w./*<>-]*$")


def _code(text: str) -> list[str]:
    """The code spans and the lines of the fenced code blocks of a Markdown text."""
    blocks = FENCE.findall(text)
    outside = FENCE.sub("", text)
    return CODE_SPAN.findall(outside) + [line for block in blocks for line in block.splitlines()]


def _markdown_pages() -> list[Path]:
    return [README, *DOC_PAGES]


def _page_id(path: Path) -> str:
    return str(path.relative_to(REPOSITORY_ROOT))


def missing_links(path: Path) -> list[str]:
    """Links of a Markdown page to local files (relative to the page) whose file does not exist."""
    missing = []
    for target in LINK.findall(path.read_text(encoding="utf-8")):
        if re.match(r"^[a-z]+:", target) or target.startswith("#"):
            continue
        if not (path.parent / target.split("#")[0]).exists():
            missing.append(target)
    return missing


def missing_paths(text: str) -> list[str]:
    """Repository paths named in code spans (``examples/x.toml``, ``tests/a/b.py::test``) that do not exist;
    ``<name>`` and ``*`` stand for any name."""
    missing = []
    for span in _code(text):
        for word in span.split():
            word = word.split("::")[0].split("#")[0].rstrip(".,;:)")
            if not REPOSITORY_PATH.match(word):
                continue
            pattern = re.sub(r"<[^>]*>|\b[A-Z]{2,}\b", "*", word)  # <name>, FILE: any name
            if not list(REPOSITORY_ROOT.glob(pattern)) and not (REPOSITORY_ROOT / pattern).exists():
                missing.append(word)
    return missing


def test_the_path_checks_find_what_they_are_for(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("[a](nowhere.md) [b](page.md) [c](https://example.org)")
    assert missing_links(page) == ["nowhere.md"]
    assert missing_paths("run `examples/no_such.toml` or `examples/koyna_el_centro.toml`") == ["examples/no_such.toml"]
    assert missing_paths("`tests/docs/test_front_door.py::test_x` and `docs/figures/eindhoven_<w>_cracks_end.png`") == []


@pytest.mark.parametrize("path", _markdown_pages(), ids=_page_id)
def test_links_and_paths_exist(path):
    text = path.read_text(encoding="utf-8")
    missing = missing_links(path) + missing_paths(text)
    assert not missing, f"{_page_id(path)} names what does not exist: {missing}"


@pytest.mark.parametrize("path", sorted(p for p in EXAMPLES.iterdir() if p.is_file()), ids=_page_id)
def test_example_headers_name_paths_that_exist(path):
    header = "\n".join(path.read_text(encoding="utf-8").splitlines()[:60])
    spans = " ".join(f"`{word}`" for word in header.split())
    assert not missing_paths(spans), f"{_page_id(path)} names what does not exist: {missing_paths(spans)}"


def _examples_table(path: Path) -> set[str]:
    """The example files of the first column of the examples table of a page."""
    return set(re.findall(r"^\| `([\w.]+)` \|", path.read_text(encoding="utf-8"), flags=re.MULTILINE))


@pytest.mark.parametrize("path", [README, DOCS / "examples.md"], ids=_page_id)
def test_examples_table_lists_every_example(path):
    on_disk = {p.name for p in EXAMPLES.iterdir() if p.is_file()}
    assert _examples_table(path) == on_disk


def unknown_commands_and_flags(text: str) -> list[str]:
    """Commands ``masonrydam X ...`` and their ``--flags`` in the code of a Markdown text that the command line
    does not have."""
    parsers = _parsers()
    unknown = []
    for code in _code(text):
        for command in re.findall(r"(?:^\s*|&&\s*|;\s*|\(\s*)masonrydam\s+([^#|&;)]*)", code):
            try:
                words = shlex.split(command)
            except ValueError:
                words = command.split()
            if not words or words[0].startswith("-") and words[0] in ("--version", "--help", "-h"):
                continue
            name = words[0]
            if len(words) > 1 and f"{name} {words[1]}" in parsers:
                name = f"{name} {words[1]}"
            if name not in parsers:
                if re.match(r"^[a-z-]+$", name):
                    unknown.append(f"masonrydam {name}")
                continue
            options = {o for action in parsers[name]._actions for o in action.option_strings}
            for word in words:
                flag = word.split("=")[0]
                if re.match(r"^--?[a-z][\w-]*$", flag) and flag not in options:
                    unknown.append(f"masonrydam {name} {flag}")
    return unknown


def test_the_command_check_finds_what_it_is_for():
    assert unknown_commands_and_flags("`masonrydam run a.toml -o b.nc --set k=1` and `masonrydam plot b.nc --mode 1`, "
                                      "`find masonrydam -name x`") == []
    assert unknown_commands_and_flags("```bash\nmasonrydam runn a.toml\nmasonrydam plot b.nc --modes 2\n```") == [
        "masonrydam runn", "masonrydam plot --modes"]


@pytest.mark.parametrize("path", _markdown_pages(), ids=_page_id)
def test_commands_and_flags_exist(path):
    unknown = unknown_commands_and_flags(path.read_text(encoding="utf-8"))
    assert not unknown, f"{_page_id(path)} names commands or flags the command line does not have: {unknown}"


def _known_keys() -> set[str]:
    """Every scene key of the reference (docs/scene.md), list markers dropped: ``stages.loads.pressure``."""
    return {k.path.replace("[]", "") for k in scene_keys()}


def unknown_scene_keys(text: str) -> list[str]:
    """Scene keys a Markdown text names that the scene language does not have: ``--set 'KEY=VALUE'`` and section
    headers ``[stages.damping]``, ``[[stages.loads]]`` in its code."""
    known = {re.sub(r"<[^>]*>", "<>", k) for k in _known_keys()}
    top = {k.split(".")[0] for k in known}
    named = []
    for code in _code(text):
        named += [k for k in re.findall(r"--set\s+'?\"?([\w.\[\]]+)=", code) if not k.isupper()]  # not KEY=VALUE
        # section headers of a scene; [tool.importlinter] or an ensemble's [execution] belong to other files
        named += [k for k in re.findall(r"^\[\[?([\w.<>]+)\]\]?$", code.strip()) if k.split(".")[0] in top]
    unknown = []
    for key in named:
        normal = re.sub(r"<[^>]*>", "<>", re.sub(r"\[\d*\]", "", key))
        if normal not in known and not any(k.startswith(normal + ".") for k in known):
            unknown.append(key)
    return unknown


def test_the_key_check_finds_what_it_is_for():
    assert unknown_scene_keys("`--set 'stages[0].loads[1].pressure=1 MPa'` and `[stages.damping]`, `[materials.<g>]`, "
                              "`--set KEY=VALUE`, `[tool.importlinter]`") == []
    assert unknown_scene_keys("`--set 'stages[0].loads[1].presure=1 MPa'` and `[[stages.load]]`") == [
        "stages[0].loads[1].presure", "stages.load"]


@pytest.mark.parametrize("path", _markdown_pages(), ids=_page_id)
def test_scene_keys_exist(path):
    unknown = unknown_scene_keys(path.read_text(encoding="utf-8"))
    assert not unknown, f"{_page_id(path)} names scene keys the scene language does not have: {unknown}"
