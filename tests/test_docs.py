"""The notes the code cites live in docs/: no reference to notes a user does not have, and every cited section exists."""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# notes that existed only outside the repository (split so that this file does not name them itself)
FORBIDDEN = ("THEORY" + ".md", "DESIGN" + ".md", "/work/" + "shared")
TEXT_SUFFIXES = {".py", ".md", ".ipynb", ".toml", ".txt", ".cfg", ".ini", ".yml", ".yaml", ".json", ".html", ""}
SKIP_DIRS = {".git", ".venv", "venv", "__pycache__", "results", "build", "dist", ".pytest_cache", ".hypothesis"}

# "docs/theory.md, sec. 4.4", "docs/theory.md sec. 1.3", "docs/theory.md, secs. 4.4 and 6.3",
# "docs/theory.md#11-fem-tolerances-and-why";
# inside docs/ the prefix is dropped: "theory.md, sec. 6.3"
NUMBER = r"\d+(?:\.\d+)*"
CITATION = re.compile(rf"(?:docs/)?(\w+)\.md,?\s+secs?\.\s+({NUMBER}(?:\s*(?:,|and)\s*{NUMBER})*)")
ANCHOR = re.compile(r"docs/(\w+)\.md#([\w\-]+)")
FILE = re.compile(r"docs/([\w\-/]+\.md)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*$", re.MULTILINE)
SECTION = re.compile(rf"^({NUMBER})\.?\s")
LINK = re.compile(r"\]\(([^)\s]+)\)")


def tracked_files() -> list[Path]:
    """Files under version control (git ls-files), or every file outside build/cache folders without git."""
    try:
        listing = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True, timeout=30)
        return [ROOT / name for name in listing.stdout.decode().split("\0") if name and (ROOT / name).is_file()]
    except (OSError, subprocess.SubprocessError):
        return [path for path in ROOT.rglob("*") if path.is_file()
                and not SKIP_DIRS.intersection(path.relative_to(ROOT).parts)
                and not any(part.endswith(".egg-info") for part in path.parts)]


def text_files() -> dict[Path, str]:
    files = {}
    for path in tracked_files():
        if path.suffix in TEXT_SUFFIXES or path.parent.name == ".ci":
            try:
                files[path] = path.read_text(encoding="utf-8")
            except UnicodeDecodeError:
                continue
    return files


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def headings(name: str) -> tuple[set[str], set[str]]:
    """Section numbers and anchors of docs/<name>.md."""
    text = (DOCS / f"{name}.md").read_text(encoding="utf-8")
    titles = [title for _, title in HEADING.findall(text)]
    numbers = {m.group(1) for m in map(SECTION.match, titles) if m}
    return numbers, {slug(title) for title in titles}


def broken_citations(text: str) -> list[str]:
    """Every 'docs/<file>.md, sec. N' (and anchor, and plain docs/<file>.md) in ``text`` that does not resolve."""
    problems = []
    for match in CITATION.finditer(text):
        name = match.group(1)
        if not (DOCS / f"{name}.md").is_file():
            if match.group(0).startswith("docs/"):
                problems.append(f"{match.group(0)!r}: no docs/{name}.md")
            continue
        numbers, _ = headings(name)
        problems += [f"{match.group(0)!r}: docs/{name}.md has no section {number}"
                     for number in re.findall(NUMBER, match.group(2)) if number not in numbers]
    for match in ANCHOR.finditer(text):
        name, anchor = match.groups()
        if not (DOCS / f"{name}.md").is_file() or anchor not in headings(name)[1]:
            problems.append(f"{match.group(0)!r}: no such anchor")
    problems += [f"{match.group(0)!r}: no such file" for match in FILE.finditer(text)
                 if not (DOCS / match.group(1)).is_file()]
    return problems


def line_of(text: str, needle: str) -> int:
    return text[:text.index(needle)].count("\n") + 1


def test_no_reference_to_notes_outside_the_repository():
    found = [f"{path.relative_to(ROOT)}:{line_of(text, word)}: {word}"
             for path, text in text_files().items() for word in FORBIDDEN if word in text]
    assert not found, "cite docs/theory.md or docs/design.md instead:\n" + "\n".join(found)


def test_every_cited_docs_section_exists():
    problems = [f"{path.relative_to(ROOT)}: {problem}"
                for path, text in text_files().items() for problem in broken_citations(text)]
    assert not problems, "\n".join(problems)


def test_the_checker_finds_a_missing_section_a_missing_file_and_a_missing_anchor():
    # built at run time so that the scan of this file does not see them
    prefix = "docs/"
    assert broken_citations(prefix + "theory.md, sec. 4.4 and " + prefix + "design.md, secs. 5.1 and 7") == []
    assert len(broken_citations(prefix + "theory.md, secs. 4.4, " + "99 and 6.3")) == 1
    assert len(broken_citations(prefix + "nothing.md, sec. 1")) == 2                 # citation and file
    assert len(broken_citations(prefix + "theory.md#no-such-heading")) == 1
    assert broken_citations(prefix + "theory.md#11-fem-tolerances-and-why") == []


def test_docs_sections_are_numbered_once_and_their_links_resolve():
    for path in sorted(DOCS.glob("*.md")):
        text = path.read_text(encoding="utf-8")
        titles = [title for _, title in HEADING.findall(text)]
        numbers = [m.group(1) for m in map(SECTION.match, titles) if m]
        assert len(numbers) == len(set(numbers)), f"{path.name}: a section number is used twice"
        anchors = {slug(title) for title in titles}
        for target in LINK.findall(text):
            if target.startswith(("http://", "https://")):
                continue
            file, _, anchor = target.partition("#")
            if file:
                assert (path.parent / file).exists(), f"{path.name}: link to missing {file}"
            if anchor and not file:
                assert anchor in anchors, f"{path.name}: link to missing anchor #{anchor}"
            elif anchor and file.endswith(".md"):
                assert anchor in headings(Path(file).stem)[1], f"{path.name}: link to missing {target}"


def test_the_readme_points_to_the_docs():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "docs/README.md" in readme
    for name in ("theory", "design", "glossary"):
        assert (DOCS / f"{name}.md").is_file()
        assert f"{name}.md" in (DOCS / "README.md").read_text(encoding="utf-8")
