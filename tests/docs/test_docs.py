"""The documentation stays true: the site builds with no warning, and every code block in it runs.

The site's pages are docs/**/*.md and the README (its home page). Their fenced code blocks:

* ``python``: run in page order in one namespace per page, in a child process whose working folder is a scratch
  folder holding links to the checkout's ``examples/``, ``scenes/``, ``benchmarks/`` and ``build_fmu.py``;
* ``bash``: run by ``bash -e`` in that folder, in page order with the Python blocks, ``python`` and
  ``prandtl-fmu`` being this interpreter and its package;
* ``toml``: a scene (or a piece of one, completed with a ``[solver]``) read by the scene reader, a sweep file by
  the sweep reader;
* ``text``: shown, not run.

A block that cannot run here (it installs software, or needs a master that is not installed) follows a line
``<!-- skip: the reason -->``; there are few. Running the blocks and building the site take minutes: they are
``slow``; the quick tests check the blocks' form and the README.
"""
from __future__ import annotations

import json
import os
import pathlib
import re
import subprocess
import sys
import textwrap
import urllib.parse
from dataclasses import dataclass
from typing import Optional

import pytest

from tests.paths import ROOT

DOCS = ROOT / "docs"
README = ROOT / "README.md"
# The README's first code block: the two commands users and CI run, never changed by the documentation.
TWO_COMMANDS = (
    'pip install ".[fmpy,plot]" && python build_fmu.py -o PrandtlElement.fmu && python examples/run_fmu.py '
    'PrandtlElement.fmu --plot paper-section-8-fmu.png\n'
    'pip install -e ".[test]" && python -m pytest -q\n'
)
LANGUAGES = ("python", "bash", "toml", "text")
MOST_SKIPPED = 14  # few, each with its reason
FENCE = re.compile(r"^(?P<indent> *)```(?P<language>\w*)\s*$")
SKIP = re.compile(r"^<!-- skip: (?P<reason>.+?) -->$")


@dataclass
class Block:
    page: pathlib.Path
    line: int
    language: str
    text: str
    skip: Optional[str]

    def __str__(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"


def pages() -> list:
    return sorted(DOCS.rglob("*.md")) + [README]


def blocks(page: pathlib.Path) -> list:
    """The fenced code blocks of a page, with the reason a ``<!-- skip: ... -->`` line above one gives."""
    lines = page.read_text(encoding="utf-8").split("\n")
    found, index = [], 0
    while index < len(lines):
        fence = FENCE.match(lines[index])
        if fence:
            indent = len(fence.group("indent"))
            end = index + 1
            while end < len(lines) and lines[end].strip() != "```":
                end += 1
            assert end < len(lines), f"{page}:{index + 1}: a code block that does not end"
            above = lines[index - 1].strip() if index else ""
            skip = SKIP.match(above)
            text = "\n".join(line[indent:] for line in lines[index + 1:end]) + "\n"
            found.append(Block(page, index + 1, fence.group("language"), text, skip.group("reason") if skip else None))
            index = end
        index += 1
    return found


def every_block() -> list:
    return [block for page in pages() for block in blocks(page)]


# ------------------------------------------------------------------------------------------------- quick checks

def test_the_readme_is_a_landing_page_of_at_most_10_kb():
    assert README.stat().st_size <= 10_240
    first = blocks(README)[0]
    assert first.language == "bash" and first.text == TWO_COMMANDS


def test_the_pages_read_as_a_site():
    """The site's text speaks to its reader, not to the project's history or its files: no "Back to the
    README" (the site has its navigation), no "issue N" (a reader has no tracker; say what was done), and a
    link to a page is named by the page's subject, not its file name ("[scene-format.md](scene-format.md)").
    Generated reports under docs/bench are left out: their tables say which run made them."""
    found = []
    for page in pages():
        if page.parent.name == "bench":
            continue
        text = page.read_text(encoding="utf-8")
        for pattern, why in ((r"Back to the \[?README", "a way back the navigation gives"),
                             (r"\b[Ii]ssues? \d+", "a tracker's number"),
                             (r"\[[^\]`]*\.md(#[^\]]*)?\]\(", "a link named by its file")):
            for match in re.finditer(pattern, text):
                line = text.count("\n", 0, match.start()) + 1
                found.append(f"{page.relative_to(ROOT)}:{line}: {why}: {match.group(0)}")
    assert found == [], "\n".join(found)


# What a user's page does not carry: the history of how it was made belongs in CHANGELOG.md and the commits.
MONTHS = ("January|February|March|April|May|June|July|August|September|October|November|December")
NOT_FOR_USERS = (
    (r"(?<![\w/.-])/tmp(?:/|\b)", "a path of a temporary folder"),
    (r"\b(?:this|the development|our) machine\b", "\"this machine\" (which? say its kind)"),
    (r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b", "a calendar date (CHANGELOG.md holds them)"),
    (rf"\b(?:{MONTHS}) [0-3]?\d(?:st|nd|rd|th)?\b|\b[0-3]?\d (?:{MONTHS})\b",
     "a calendar date (CHANGELOG.md holds them)"),
)


def lines_not_for_users(page: pathlib.Path, text: str) -> list:
    """``page:line: why: what`` for every match of :data:`NOT_FOR_USERS` in ``text``."""
    found = []
    for pattern, why in NOT_FOR_USERS:
        for match in re.finditer(pattern, text, flags=re.IGNORECASE if "machine" in pattern else 0):
            line = text.count("\n", 0, match.start()) + 1
            found.append(f"{page.relative_to(ROOT) if page.is_absolute() else page}:{line}: {why}: {match.group(0)}")
    return found


def test_the_pages_carry_no_history_of_their_making():
    """No temporary folder's path, no "this machine", no calendar date in the README or the site's pages: a
    user reads what is true now and on which kind of machine; when a thing changed is CHANGELOG.md's."""
    found = []
    for page in pages():
        found += lines_not_for_users(page, page.read_text(encoding="utf-8"))
    assert found == [], "\n".join(found)


def test_the_history_rule_finds_what_it_refuses():
    """The rule above, on text written here: it must find each kind (a rule that finds nothing passes all)."""
    refused = ("a /tmp script", "written to /tmp/run.csv", "on this machine", "on the development machine",
               "(2026-11-29, evening)",
               "since November 25", "on 3 December")
    kept = ("a temporary folder (mktemp -d)", "x_tmp = 1", "a 2-core x86-64 machine", "version 2.0.1",
            "the 1e-3 tolerance", "/usr/tmpfile")
    for text in refused:
        assert lines_not_for_users(pathlib.Path("page.md"), text), text
    for text in kept:
        assert not lines_not_for_users(pathlib.Path("page.md"), text), text


def slug(heading: str) -> str:
    """The anchor Python-Markdown's table of contents gives a heading (its default ``slugify``)."""
    import unicodedata
    text = re.sub(r"`|\*\*|\*", "", heading)
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    text = re.sub(r"[^\w\s-]", "", text).strip().lower()
    return re.sub(r"[-\s]+", "-", text)


def anchors(page: pathlib.Path) -> set:
    """The anchors of a page's headings (outside code blocks; a repeated heading gets _1, _2 ...)."""
    seen, found, fenced = {}, set(), False
    for line in page.read_text(encoding="utf-8").split("\n"):
        if FENCE.match(line) or line.strip() == "```":
            fenced = not fenced
            continue
        heading = re.match(r"^#{1,6} (.+?)\s*#*\s*$", line)
        if heading and not fenced:
            base = slug(heading.group(1))
            name = base if base not in seen else f"{base}_{seen[base]}"
            seen[base] = seen.get(base, 0) + 1
            found.add(name)
    found.update(re.findall(r'\{ *#([\w-]+) *\}|<a (?:name|id)="([\w-]+)"', page.read_text(encoding="utf-8")) and
                 [a or b for a, b in re.findall(r'\{ *#([\w-]+) *\}|<a (?:name|id)="([\w-]+)"',
                                                 page.read_text(encoding="utf-8"))])
    return found


def broken_links(page: pathlib.Path) -> list:
    """``page:line: target`` for every relative link of the page (outside code) to a file that does not exist,
    or to an anchor that no heading of the target page makes (a page docs/gen_pages.py completes at build
    time is checked by the site's build)."""
    text = page.read_text(encoding="utf-8")
    text = re.sub(r"```.*?```", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    lines, code = text.split("\n"), False
    for index, line in enumerate(lines):  # indented code: 4 spaces after a blank line or more code
        code = line.startswith("    ") and (code or index == 0 or not lines[index - 1].strip())
        lines[index] = "" if code else line
    text = re.sub(r"`[^`\n]*`", "``", "\n".join(lines))
    found = []
    for match in re.finditer(r"\]\(([^)\s]+)(?: \"[^\"]*\")?\)", text):
        target = match.group(1)
        if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:", target):
            continue  # another site, a mailto:
        path, _, anchor = target.partition("#")
        where = (page.parent / urllib.parse.unquote(path)).resolve() if path else page
        line = text.count("\n", 0, match.start()) + 1
        if not where.exists():
            found.append(f"{page.relative_to(ROOT)}:{line}: no such file: {target}")
        elif (anchor and where.suffix == ".md" and anchor not in anchors(where)
              and "<!-- generated:" not in where.read_text(encoding="utf-8")):  # its headings come at build time
            found.append(f"{page.relative_to(ROOT)}:{line}: no such anchor: {target}")
    return found


def test_every_link_of_the_pages_opens_a_file_and_its_anchor():
    """Relative links of the README and the site's pages, anchors included (mkdocs checks the built site too,
    in the slow suite and CI: this is the check a writer meets in seconds)."""
    found = [problem for page in pages() for problem in broken_links(page)]
    assert found == [], "\n".join(found)


def test_the_link_check_finds_a_broken_file_and_anchor(tmp_path, monkeypatch):
    monkeypatch.setattr(sys.modules[__name__], "ROOT", tmp_path)
    (tmp_path / "a.md").write_text("# A title `with code`\n\n## Second: part (two)\n\ntext\n")
    (tmp_path / "b.md").write_text("[ok](a.md#a-title-with-code) [ok](a.md#second-part-two) [bad](a.md#nope) "
                                   "[gone](c.md) [web](https://example.org/x.md#y)\n```text\n[not](d.md)\n```\n")
    found = broken_links(tmp_path / "b.md")
    assert len(found) == 2 and "a.md#nope" in found[0] and "c.md" in found[1], found


def test_every_block_has_a_language_and_the_skipped_ones_a_reason():
    found = every_block()
    assert len(found) >= 30
    for block in found:
        assert block.language in LANGUAGES, f"{block}: ```{block.language}"
    for page in pages():
        text = page.read_text(encoding="utf-8")
        for match in re.finditer(r"<!-- skip:(.*?)-->\n(.*)", text):
            assert match.group(1).strip(), f"{page}: a skip marker without its reason"
            assert FENCE.match(match.group(2)), f"{page}: a skip marker not right above a code block"
    skipped = [block for block in found if block.skip]
    assert len(skipped) <= MOST_SKIPPED, [str(block) for block in skipped]


def test_every_python_block_compiles():
    for block in every_block():
        if block.language == "python":
            compile(block.text, str(block), "exec")


def _is_sweep(document: dict) -> bool:
    return bool({"grid", "random", "seeds", "keep", "statistics", "law", "tasks"} & set(document))


def scene_of_block(block: Block) -> str:
    """The TOML of a scene block, completed where it shows one table or a few: a ``[solver]`` and, for an element
    without ``[mass]``, a mass (the pieces show tables, not whole scenes)."""
    from prandtl_fmu.scene import toml_document

    document = toml_document(block.text, str(block))
    text = block.text
    if "solver" not in document:
        text += '\n[solver]\nstepper = "implicit"\nstep = 0.01\nstop_time = 1.0\noutput_interval = 0.1\n'
        network = "network" in document or "chain" in document
        if not network and "mass" not in document and "fmu" not in document:
            text += "\n[mass]\nm = 1.0\n"
    return text


def test_every_toml_block_is_read_by_the_scene_or_sweep_reader():
    from prandtl_fmu import parse_scene
    from prandtl_fmu.scene import toml_document
    from prandtl_fmu.sweep.spec import parse_spec

    checked = 0
    for block in every_block():
        if block.language != "toml":
            continue
        document = toml_document(block.text, str(block))
        if _is_sweep(document):
            parse_spec(document, str(block))
        else:
            parse_scene(scene_of_block(block), source=str(block), check_stepper="solver" in document)
        checked += 1
    assert checked >= 8


def test_the_block_reader_finds_fences_markers_and_indented_blocks(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("text\n\n<!-- skip: needs a master -->\n```bash\nmaster run\n```\n\n* item:\n\n  ```python\n"
                    "  x = 1\n  ```\n", encoding="utf-8")
    found = blocks(page)
    assert [(b.language, b.text, b.skip) for b in found] == [("bash", "master run\n", "needs a master"),
                                                             ("python", "x = 1\n", None)]


# -------------------------------------------------------------------------------------------------- slow checks

@pytest.mark.slow
def test_the_site_builds_with_no_warning(tmp_path):
    try:
        import mkdocs  # noqa: F401  (its theme and plugins missing, with mkdocs there, fail the build: a broken extra)
    except ImportError:
        print("skipped: mkdocs is not installed: pip install -e \".[docs]\"")
        pytest.skip("mkdocs is not installed: pip install -e \".[docs]\"")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=1800,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))
    assert done.returncode == 0, done.stdout[-5000:] + done.stderr[-5000:]
    assert "WARNING" not in done.stderr
    site = tmp_path / "site"
    for page in ("index.html", "scene-reference.html", "fmu-variables.html", "api.html", "steppers.html"):
        assert (site / page).is_file(), page
    reference = (site / "scene-reference.html").read_text(encoding="utf-8")
    assert "stribeck_velocity" in reference and "network.branch" in reference
    assert "noise_seed" in (site / "fmu-variables.html").read_text(encoding="utf-8")
    # opened from disk (file://), every relative link and image of every page opens a file: no folder URL
    # (a browser shows a folder listing there) and no link to a page that is not built. The 404 page is the
    # server's, its links absolute by design.
    broken = {}
    for page in site.rglob("*.html"):
        if page.name == "404.html":
            continue
        for target in re.findall(r'(?:href|src)="([^"]+)"', page.read_text(encoding="utf-8", errors="replace")):
            if re.match(r"^[a-zA-Z][a-zA-Z0-9+.-]*:|^#|^//", target):
                continue  # another site, a mailto:, an anchor of the page itself
            path = urllib.parse.unquote(target.split("#")[0].split("?")[0])
            if path and not (page.parent / path).resolve().is_file():
                broken.setdefault(str(page.relative_to(site)), []).append(target)
    assert broken == {}, broken


# What runs a page's blocks in order, in a child process: Python blocks in one namespace, bash blocks by bash.
# (Guarded: a block that starts worker processes, dask's, has them import this script again.)
RUNNER = r'''
import json, subprocess, sys, traceback


def main():
    blocks = json.load(open(sys.argv[1]))
    namespace = {"__name__": "__main__"}
    for block in blocks:
        print(f"=== {block['where']} ({block['language']})", flush=True)
        if block["language"] == "python":
            try:
                exec(compile(block["text"], block["where"], "exec"), namespace)
            except BaseException:
                traceback.print_exc()
                sys.exit(f"{block['where']}: the Python block failed")
        else:
            done = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", block["text"]])
            if done.returncode:
                sys.exit(f"{block['where']}: the bash block exited {done.returncode}")


if __name__ == "__main__":
    main()
'''


def _scratch(tmp_path: pathlib.Path) -> dict:
    """A working folder with the checkout's examples at hand, and ``python``, ``prandtl-fmu`` on PATH: this
    interpreter and its package. Returns the environment to run in."""
    for name in ("examples", "scenes", "benchmarks", "build_fmu.py"):
        (tmp_path / name).symlink_to(ROOT / name)
    tools = tmp_path / ".bin"
    tools.mkdir()
    for name, line in (("python", f'exec "{sys.executable}" "$@"'),
                       ("python3", f'exec "{sys.executable}" "$@"'),
                       ("prandtl-fmu", f'exec "{sys.executable}" -m prandtl_fmu "$@"')):
        (tools / name).write_text(f"#!/bin/sh\n{line}\n")
        (tools / name).chmod(0o755)
    return dict(os.environ, PATH=f"{tools}{os.pathsep}{os.environ.get('PATH', '')}", MPLBACKEND="Agg",
                PYTHONPATH=os.pathsep.join([str(ROOT)] + [p for p in [os.environ.get("PYTHONPATH")] if p]))


RUNNABLE = [page for page in pages() if any(b.language in ("python", "bash") and not b.skip for b in blocks(page))]


@pytest.mark.slow
@pytest.mark.parametrize("page", RUNNABLE, ids=[str(page.relative_to(ROOT)) for page in RUNNABLE])
def test_the_code_blocks_of_a_page_run(page, tmp_path):
    """Every Python and bash block of the page, in order, in a scratch folder (see the module docstring)."""
    work = tmp_path / "work"
    work.mkdir()
    env = _scratch(work)
    runnable = [{"where": str(block), "language": block.language, "text": block.text}
                for block in blocks(page) if block.language in ("python", "bash") and not block.skip]
    (tmp_path / "blocks.json").write_text(json.dumps(runnable))
    (tmp_path / "runner.py").write_text(textwrap.dedent(RUNNER))
    done = subprocess.run([sys.executable, str(tmp_path / "runner.py"), str(tmp_path / "blocks.json")], cwd=work,
                          env=env, capture_output=True, text=True, timeout=3600)
    assert done.returncode == 0, done.stdout[-6000:] + done.stderr[-6000:]
