"""The documentation checked against the repository (ctest: docs_links and readme_code_blocks).

    python3 tests/docs/check_docs.py links SOURCE_DIR
    python3 tests/docs/check_docs.py blocks SOURCE_DIR SOFTBAKE_BINARY

`links`: every relative link and image in README.md and docs/*.md names a file or folder of the
repository, and every `#anchor` in such a link names a heading of the Markdown file it points to,
by GitHub's rule (the heading's text in lower case, punctuation but hyphens and underscores
dropped, spaces to hyphens, "-1", "-2" ... after repeats). Links inside code are not links. The
README links to every page of docs/, and still opens with the two commands (SETUP_BLOCK).

`blocks`: every ```sh or ```bash block of the README is of one of two kinds. A block whose
commands all start with `softbake ` or `build/cli/softbake ` is run under `bash -e`, against
SOFTBAKE_BINARY, in a new temporary folder where the repository's top-level files are linked in
(so `examples/...` resolves, and what the commands write stays out of the tree). A block whose
commands all start with `bash scripts/` is not run: those scripts install packages, build and run
the whole suite (the two commands at the top of the README), which a test inside that suite cannot
do. Any other block fails, so a new block gets one rule or the other.

A missing file fails the check; nothing is skipped. Exit status 0 when everything holds, 1 with
every problem listed otherwise.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unicodedata
from pathlib import Path
from urllib.parse import unquote

# The README's first code block, as CI and newcomers use it (README.md, top).
SETUP_BLOCK = (
    "bash scripts/run.sh     # simulates the built-in scene (two soft balls, 240 frames) into ./out\n"
    "bash scripts/test.sh    # runs the whole test suite (ctest)\n"
)
RUN_PREFIXES = ("softbake ", "build/cli/softbake ")
EXEMPT_PREFIX = "bash scripts/"
SHELL_LANGUAGES = {"sh", "bash", "shell"}
BLOCK_SECONDS = 120

FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})\s*([^`\s]*)")
HEADING = re.compile(r"^ {0,3}(#{1,6})[ \t]+(.*?)[ \t]*#*[ \t]*$")
# [text](target "title") and ![alt](target); the text may hold one level of brackets.
INLINE_LINK = re.compile(
    r"\[((?:[^\[\]]|\[[^\[\]]*\])*)\]\(\s*(<[^>]*>|[^\s()]*(?:\([^\s()]*\)[^\s()]*)*)"
    r"(?:\s+(?:\"[^\"]*\"|'[^']*'))?\s*\)")
REFERENCE_DEFINITION = re.compile(r"^ {0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)", re.MULTILINE)
HTML_SOURCE = re.compile(r"<(?:img|a)\b[^>]*?\b(?:src|href)=\"([^\"]*)\"", re.IGNORECASE)
CODE_SPAN = re.compile(r"(`+)(?:(?!\1).)+?\1", re.DOTALL)
SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


class Problems(list):
    def add(self, where, what):
        self.append(f"{where}: {what}")


def read(path, problems):
    try:
        return path.read_text(encoding="utf-8")
    except OSError as error:
        problems.add(path, f"cannot read it ({error.strerror})")
        return None


def fenced_blocks(text):
    """Yields (first line number, info word, body) for each fenced code block."""
    lines = text.split("\n")
    i = 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if not opening:
            i += 1
            continue
        fence, info = opening.group(1), opening.group(2)
        body = []
        j = i + 1
        while j < len(lines) and not closes(fence, lines[j]):
            body.append(lines[j])
            j += 1
        yield i + 1, info.lower(), "\n".join(body) + "\n"
        i = j + 1


def closes(fence, line):
    """Whether `line` closes a block opened by `fence` (the same character, at least as many)."""
    return re.match(r"^ {0,3}" + re.escape(fence[0]) + "{" + str(len(fence)) + r",}\s*$", line)


def outside_blocks(text):
    """The text with fenced code blocks blanked out, line numbers kept: a `#` line or a link in
    a block is neither heading nor link."""
    lines = text.split("\n")
    fence = None
    for n, line in enumerate(lines):
        opening = FENCE.match(line)
        if fence is None and opening:
            fence = opening.group(1)
            lines[n] = ""
        elif fence is not None:
            if closes(fence, line):
                fence = None
            lines[n] = ""
    return "\n".join(lines)


def prose(text):
    """The text outside code: fenced blocks and inline code spans blanked out."""
    blank = lambda m: re.sub(r"[^\n]", " ", m.group(0))
    # A code span ends with its paragraph: blank them paragraph by paragraph.
    return "\n\n".join(CODE_SPAN.sub(blank, p) for p in outside_blocks(text).split("\n\n"))


def slug(heading):
    """GitHub's anchor for a heading's text."""
    text = INLINE_LINK.sub(lambda m: m.group(1), heading)  # a link in a heading: its text
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    kept = "".join(c for c in text if c in " -" or unicodedata.category(c)[0] in "LMN" or
                   unicodedata.category(c) == "Pc")
    return kept.replace(" ", "-")


def anchors(text):
    """Every heading anchor of a Markdown file, repeats numbered as GitHub numbers them."""
    found, seen = set(), {}
    for line in outside_blocks(text).split("\n"):
        match = HEADING.match(line)
        if not match:
            continue
        base = slug(match.group(2))
        count = seen.get(base, 0)
        seen[base] = count + 1
        found.add(base if count == 0 else f"{base}-{count}")
    return found


def link_targets(text):
    """Yields (line number, target) for every link, image and reference definition."""
    visible = prose(text)
    line_of = lambda offset: visible.count("\n", 0, offset) + 1
    for match in INLINE_LINK.finditer(visible):
        yield line_of(match.start()), match.group(2).strip("<>")
    for match in REFERENCE_DEFINITION.finditer(visible):
        yield line_of(match.start()), match.group(1).strip("<>")
    for match in HTML_SOURCE.finditer(visible):
        yield line_of(match.start()), match.group(1)


def check_links(root):
    problems = Problems()
    readme = root / "README.md"
    docs = sorted((root / "docs").glob("*.md"))
    if not docs:
        problems.add(root / "docs", "no Markdown pages (docs/*.md)")
    anchor_cache = {}
    checked = 0
    linked_from_readme = set()
    for page in [readme, *docs]:
        text = read(page, problems)
        if text is None:
            continue
        for line, target in link_targets(text):
            where = f"{page.relative_to(root)}:{line}"
            if SCHEME.match(target) or target.startswith("//"):
                continue  # http:, https:, mailto: ... are outside the repository
            checked += 1
            path_part, _, anchor = target.partition("#")
            if not path_part and not anchor:
                problems.add(where, "an empty link")
                continue
            path_part = unquote(path_part)
            if path_part.startswith("/"):
                resolved = (root / path_part.lstrip("/")).resolve()
            elif path_part:
                resolved = (page.parent / path_part).resolve()
            else:
                resolved = page.resolve()
            if root.resolve() not in [resolved, *resolved.parents]:
                problems.add(where, f"'{target}' points outside the repository")
                continue
            if not resolved.exists():
                problems.add(where, f"'{target}': no file {resolved.relative_to(root.resolve())}")
                continue
            if page == readme:
                linked_from_readme.add(resolved)
            if not anchor:
                continue
            if resolved.suffix != ".md" or not resolved.is_file():
                problems.add(where, f"'{target}': an anchor into a file that is not Markdown")
                continue
            if resolved not in anchor_cache:
                anchor_cache[resolved] = anchors(resolved.read_text(encoding="utf-8"))
            if unquote(anchor) not in anchor_cache[resolved]:
                problems.add(where, f"'{target}': no heading '#{anchor}' in "
                                    f"{resolved.relative_to(root.resolve())}")
    for page in docs:
        if page.resolve() not in linked_from_readme:
            problems.add(readme.relative_to(root), f"no link to {page.relative_to(root)}")
    text = read(readme, problems)
    if text is not None:
        blocks = list(fenced_blocks(text))
        first_heading = next((n for n, line in enumerate(text.split("\n"), 1)
                              if line.startswith("## ")), None)
        if not blocks or blocks[0][2] != SETUP_BLOCK or (first_heading and
                                                          blocks[0][0] > first_heading):
            problems.add("README.md", "does not open with the two commands:\n" + SETUP_BLOCK)
    print(f"check_docs: checked {checked} links of README.md and docs/ ({len(docs)} pages)")
    return problems


def commands(block):
    """The block's commands: continuation lines joined, comments and blank lines dropped."""
    joined = re.sub(r"\\\n", " ", block)
    return [line.strip() for line in joined.split("\n")
            if line.strip() and not line.strip().startswith("#")]


def check_blocks(root, binary):
    problems = Problems()
    readme = root / "README.md"
    if not binary.is_file() or not os.access(binary, os.X_OK):
        problems.add(binary, "no softbake binary there")
        return problems
    text = read(readme, problems)
    if text is None:
        return problems
    ran = 0
    for line, language, body in fenced_blocks(text):
        if language not in SHELL_LANGUAGES:
            continue
        where = f"README.md:{line}"
        lines = commands(body)
        if lines and all(c.startswith(EXEMPT_PREFIX) for c in lines):
            print(f"check_docs: {where}: not run (`bash scripts/...` sets up, builds or tests)")
            continue
        if not lines or not all(c.startswith(RUN_PREFIXES) for c in lines):
            problems.add(where, "a shell block must start every command with `softbake ` or "
                                "`build/cli/softbake ` (run by this test) or with `bash scripts/` "
                                "(set-up, not run):\n" + body)
            continue
        ran += 1
        problems.extend(run_block(root, binary, where, body))
    if ran == 0 and not problems:
        problems.add("README.md", "no `softbake` block to run")
    print(f"check_docs: ran {ran} README block(s)")
    return problems


def run_block(root, binary, where, body):
    """Runs one block in a new folder holding links to the repository's top-level files."""
    problems = Problems()
    scratch = Path(tempfile.mkdtemp(prefix="softbake_readme_"))
    try:
        bin_dir = scratch / "bin"
        work = scratch / "work"
        bin_dir.mkdir()
        work.mkdir()
        (bin_dir / "softbake").symlink_to(binary)
        for entry in root.iterdir():
            if entry.name.startswith(".") or entry.name.startswith("build") or entry.name == "out":
                continue
            (work / entry.name).symlink_to(entry)
        (work / "build" / "cli").mkdir(parents=True)
        (work / "build" / "cli" / "softbake").symlink_to(binary)
        environment = dict(os.environ, PATH=f"{bin_dir}{os.pathsep}{os.environ.get('PATH', '')}")
        print(f"check_docs: {where}: running\n{body}", end="")
        try:
            result = subprocess.run(["bash", "-e", "-o", "pipefail", "-c", body], cwd=work,
                                    env=environment, capture_output=True, text=True,
                                    timeout=BLOCK_SECONDS)
        except subprocess.TimeoutExpired:
            problems.add(where, f"still running after {BLOCK_SECONDS} s:\n{body}")
            return problems
        if result.returncode != 0:
            problems.add(where, f"exit status {result.returncode}:\n{body}"
                                f"--- output ---\n{result.stdout}{result.stderr}")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    return problems


def main(arguments):
    if len(arguments) < 2 or arguments[0] not in ("links", "blocks") or \
            (arguments[0] == "blocks") != (len(arguments) == 3) or len(arguments) > 3:
        print(__doc__, file=sys.stderr)
        return 2
    root = Path(arguments[1]).resolve()
    if arguments[0] == "links":
        problems = check_links(root)
    else:
        problems = check_blocks(root, Path(arguments[2]))
    for problem in problems:
        print(f"check_docs: {problem}", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
