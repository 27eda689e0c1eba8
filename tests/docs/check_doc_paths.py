#!/usr/bin/env python3
"""The repository stands on its own and its docs do not rot: every
repository path that a tracked file cites exists, and nothing tracked refers
to the side folder next to the checkout.

  check_doc_paths.py [--repo DIR]               the check
  check_doc_paths.py [--repo DIR] --self-test   runs the check on a small
      temporary git repository with known breakage and fails unless exactly
      that breakage is reported

Files: `git ls-files --cached --others --exclude-standard` (tracked files and
new files git does not ignore), less binary files and anything under
fuzz/corpus/ or the web client's node_modules/.

Citations, in code and docs alike (the extensions in TEXT_SUFFIXES, Makefile
and Dockerfile*):
  - repository paths that start with one of TOP_FOLDERS, such as
    `docs/ALGORITHM.md`, `server/warp/` or `shaders/raycast_body.glsl`;
  - in .md files, relative markdown links such as [x](FEM.md) or
    [x](../../docs/MESH.md), resolved against the linking file's folder.
Each must be a file the listing has, or a folder holding one.

Side folder: any mention, in any listed text file, of the folder beside the
checkout (SIDE_FOLDERS) is an error, cited path or not.

Prints every failure as `FILE:LINE: cites PATH, which does not exist` (or
`FILE:LINE: cites PATH, which refers to the side folder`) and exits 1 when
there is any; else prints a one-line summary and exits 0."""

import argparse
import fnmatch
import os
import posixpath
import re
import subprocess
import sys
import tempfile

# The top-level folders whose paths are checked when cited.
TOP_FOLDERS = ("docs", "shaders", "server", "tests", "client", "proto", "bench",
               "scripts", "docker", "cmake")

# Files whose citations are checked (by suffix, or by name).
TEXT_SUFFIXES = (".md", ".h", ".cc", ".glsl", ".comp", ".proto", ".txt", ".cmake",
                 ".sh", ".py", ".js", ".mjs", ".json", ".yaml", ".yml")
TEXT_NAMES = ("Makefile",)
TEXT_NAME_PREFIXES = ("Dockerfile",)

# Folders never scanned: fuzzer inputs (binary-ish, not prose) and installed
# npm packages (not ours).
NODE_MODULES = "client/web/" + "node_modules"
SKIPPED_PREFIXES = ("fuzz/corpus/", NODE_MODULES + "/")

# The side folder. Spelled in pieces so that this file does not mention it.
SIDE_FOLDERS = (".." + "/shared", "/work" + "/shared")

# A cited repository path. It starts with one of TOP_FOLDERS and must not be
# preceded by a path character ('/', '.', '-', '_', a letter or digit): in
# `build/server/service/vpm-server` (a build output) or
# `${CMAKE_BINARY_DIR}/shaders/...` no repository path starts at "server" or
# "shaders". The body is path characters plus, so that they can be
# recognized below, brace groups (`camera.{h,cc}`), placeholders
# (`<folder>`), globs (`*`, `?`) and `$`.
_PATH_CHAR = r"[A-Za-z0-9_.\-/*?$]"
CITED_PATH = re.compile(
    r"(?<![A-Za-z0-9_./\-])"
    r"((?:" + "|".join(TOP_FOLDERS) + r")/"
    r"(?:" + _PATH_CHAR + r"|\{[^{}\s]*\}|<[^<>\s]*>)*)")

# A markdown inline link or image, [text](target "title"), and a reference
# definition, [label]: target.
MD_INLINE_LINK = re.compile(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
MD_REFERENCE_LINK = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s|$)")
# Link targets that are not repository files: web addresses, mail, and pure
# anchors within the page.
EXTERNAL_LINK = re.compile(r"^(?:https?:|mailto:|#)", re.IGNORECASE)

# Characters stripped from the end of a cited path: sentence punctuation and
# the quotes or brackets around it.
TRAILING_PUNCTUATION = ".,;:)`'\""


def list_files(repo):
    """Repository-relative paths of the tracked files and of the new files
    git does not ignore, that exist in the working tree."""
    result = subprocess.run(
        ["git", "-C", repo, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
        capture_output=True, check=False)
    if result.returncode != 0:
        sys.exit(f"git ls-files failed in {repo} (not a git checkout?): "
                 f"{result.stderr.decode(errors='replace').strip()}")
    out = result.stdout.decode("utf-8", "surrogateescape")
    names = sorted({n for n in out.split("\0") if n})
    # A file deleted in the working tree but still in the index is not there.
    return [n for n in names if os.path.isfile(os.path.join(repo, n))]


def is_skipped(name):
    return name.startswith(SKIPPED_PREFIXES)


def is_cited_file_type(name):
    base = posixpath.basename(name)
    return (base.endswith(TEXT_SUFFIXES) or base in TEXT_NAMES
            or base.startswith(TEXT_NAME_PREFIXES))


def read_text(path):
    """The file's text, or None when it is binary (a NUL byte, or not UTF-8)."""
    with open(path, "rb") as f:
        data = f.read()
    if b"\0" in data:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return None


class Repo:
    """The listed files, and the folders that hold them."""

    def __init__(self, files):
        self.files = set(files)
        self.folders = set()
        for name in files:
            parts = name.split("/")[:-1]
            for i in range(1, len(parts) + 1):
                self.folders.add("/".join(parts[:i]))

    def exists(self, path):
        """Whether `path` (repository-relative, possibly ending in '/') is a
        listed file or a folder holding one."""
        path = posixpath.normpath(path)
        return path in self.files or path in self.folders

    def glob_matches(self, pattern):
        pattern = posixpath.normpath(pattern)
        return any(fnmatch.fnmatchcase(n, pattern) for n in self.files | self.folders)


def expand_braces(path):
    """`server/raycast/camera.{h,cc}` -> the .h and the .cc; braces nest and
    repeat. A brace group with no comma (`${NAME}`) is left as it is."""
    match = re.search(r"\{([^{}]*,[^{}]*)\}", path)
    if not match:
        return [path]
    out = []
    for alternative in match.group(1).split(","):
        out += expand_braces(path[:match.start()] + alternative + path[match.end():])
    return out


def strip_suffixes(path):
    """Strips trailing punctuation, a `#anchor` and a `:line` suffix."""
    path = path.split("#", 1)[0]
    path = re.sub(r":\d+(?:[:-]\d+)*$", "", path)
    return path.rstrip(TRAILING_PUNCTUATION)


def classify_citation(repo, path):
    """None when `path` (repository-relative) is fine or is not a repository
    path after all; else the path as reported."""
    # `npm ci` installs the web client's packages there (scripts/install-web.sh);
    # git ignores the folder, so it is cited but never listed.
    if path == NODE_MODULES or path.startswith(NODE_MODULES + "/"):
        return None
    # Placeholders and variables (`server/<folder>/README.md`, `tests/$name`)
    # name no one path; brace groups left after expansion are `${...}`.
    if any(c in path for c in "<>${}"):
        return None
    # Generated shader headers (`shaders/<stem>.spv.h`, written by
    # cmake/Shaders.cmake into the build tree) are build outputs.
    if path.endswith(".spv.h"):
        return None
    # A glob (`shaders/raycast_*.comp`) must match at least one file.
    if any(c in path for c in "*?"):
        return None if repo.glob_matches(path) else path
    return None if repo.exists(path) else path


def scan_text(name, text, repo):
    """(line, path, kind) for every failure in one file's text; kind is
    'missing' or 'side'. Also returns the number of citations checked."""
    failures = []
    checked = 0
    folder = posixpath.dirname(name)
    is_markdown = name.endswith(".md")
    cites_paths = is_cited_file_type(name)
    for number, line in enumerate(text.splitlines(), 1):
        for side in SIDE_FOLDERS:
            for m in re.finditer(re.escape(side) + r"[A-Za-z0-9_.\-/]*", line):
                failures.append((number, strip_suffixes(m.group(0)) or side, "side"))
                checked += 1
        if not cites_paths:
            continue
        for m in CITED_PATH.finditer(line):
            # `# syntax=docker/dockerfile:1` (a Dockerfile's first line) names
            # BuildKit's frontend image, not a file under docker/.
            if line[:m.start()].endswith("syntax="):
                continue
            raw = strip_suffixes(m.group(1))
            if "/" not in raw:
                continue
            for path in expand_braces(raw):
                path = strip_suffixes(path)
                checked += 1
                bad = classify_citation(repo, path)
                if bad is not None:
                    failures.append((number, bad, "missing"))
        if not is_markdown:
            continue
        targets = [m.group(1) for m in MD_INLINE_LINK.finditer(line)]
        targets += [m.group(1) for m in MD_REFERENCE_LINK.finditer(line)]
        for target in targets:
            if EXTERNAL_LINK.match(target):
                continue
            # Already reported as a side-folder mention.
            if any(side in target for side in SIDE_FOLDERS):
                continue
            target = strip_suffixes(target)
            if not target:
                continue
            checked += 1
            resolved = posixpath.normpath(posixpath.join(folder, target))
            if resolved.startswith("../") or resolved == "..":
                failures.append((number, target, "missing"))
                continue
            bad = classify_citation(repo, resolved)
            if bad is not None:
                failures.append((number, target, "missing"))
    # A path cited twice on one line (a link whose text is its target) is one failure.
    return sorted(set(failures), key=failures.index), checked


def run_check(repo_dir):
    """(failures, files scanned, citations checked); failures are
    (file, line, path, kind)."""
    names = list_files(repo_dir)
    repo = Repo(names)
    failures = []
    scanned = checked = 0
    for name in names:
        if is_skipped(name):
            continue
        text = read_text(os.path.join(repo_dir, name))
        if text is None:
            continue
        scanned += 1
        found, count = scan_text(name, text, repo)
        checked += count
        failures += [(name, line, path, kind) for line, path, kind in found]
    return failures, scanned, checked


def format_failure(name, line, path, kind):
    if kind == "side":
        return f"{name}:{line}: cites {path}, which refers to the side folder"
    return f"{name}:{line}: cites {path}, which does not exist"


def self_test():
    """Runs the check on a temporary repository with (a) a doc citing an
    existing path, (b) a doc citing a missing docs/ file, (c) a code comment
    citing a missing server/ header, (d) a markdown link to a missing file and
    (e) a file naming the side folder; passes when exactly (b)-(e) are
    reported. The cited paths are spelled in pieces so that this file itself
    cites nothing missing."""
    missing_doc = "docs" + "/MISSING.md"
    missing_header = "server" + "/nowhere/x.h"
    side_path = ".." + "/shared/docs/ALGORITHM.md"
    files = {
        "docs/ALGORITHM.md": "# Algorithm\n",
        "server/mesh/decimate.h": "#pragma once\n",
        # (a) cites existing paths, in the forms the check must accept.
        "notes/good.md": (
            "See docs/ALGORITHM.md, `server/mesh/decimate.h:12` and server/mesh/.\n"
            "Also [it](../docs/ALGORITHM.md#steps), [next](misses.md), [top](#top),\n"
            "`server/mesh/decimate.{h,cc}`, `docs/*.md`, `server/<folder>/README.md`,\n"
            "build/server/mesh/vpm, `shaders/<stem>.spv.h` and https://x.org/a.md.\n"
            f"# syntax=docker/dockerfile:1, {NODE_MODULES}/.bin; [a](<../docs/ALGORITHM.md>).\n"),
        # (b)
        "notes/misses.md": f"# Misses\n\nThe plan is in {missing_doc}.\n",
        # (c)
        "server/mesh/decimate.cc": f"// Declared in {missing_header}.\nint x;\n",
        # (d)
        "notes/links.md": "# Links\n\nSee [the FEM](GONE.md#top).\n",
        # (e)
        "run.sh": f"#!/bin/sh\ncat {side_path}\n",
    }
    expected = {
        ("notes/misses.md", 3, missing_doc, "missing"),
        ("server/mesh/decimate.cc", 1, missing_header, "missing"),
        ("notes/links.md", 3, "GONE.md", "missing"),
        ("run.sh", 2, side_path, "side"),
    }
    with tempfile.TemporaryDirectory() as tmp:
        for name, text in files.items():
            os.makedirs(os.path.join(tmp, posixpath.dirname(name)), exist_ok=True)
            with open(os.path.join(tmp, name), "w", encoding="utf-8") as f:
                f.write(text)
        env = dict(os.environ, GIT_AUTHOR_NAME="t", GIT_AUTHOR_EMAIL="t@t",
                   GIT_COMMITTER_NAME="t", GIT_COMMITTER_EMAIL="t@t")
        for cmd in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "self-test"]):
            subprocess.run(["git", "-C", tmp, "-c", "commit.gpgsign=false"] + cmd,
                           check=True, env=env, capture_output=True)
        failures, scanned, checked = run_check(tmp)
    got = set(failures)
    for failure in sorted(got):
        print("reported:", format_failure(*failure))
    ok = True
    for failure in sorted(expected - got):
        print("NOT REPORTED:", format_failure(*failure))
        ok = False
    for failure in sorted(got - expected):
        print("FALSE POSITIVE:", format_failure(*failure))
        ok = False
    if len(failures) != len(got):
        print("DUPLICATES:", failures)
        ok = False
    print(f"self-test {'passed' if ok else 'FAILED'}: {len(expected)} expected failures, "
          f"{len(got)} reported, {scanned} files scanned, {checked} citations checked")
    return 0 if ok else 1


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    top = subprocess.run(["git", "-C", here, "rev-parse", "--show-toplevel"],
                         capture_output=True, text=True, check=False)
    default_repo = (top.stdout.strip() if top.returncode == 0
                    else os.path.dirname(os.path.dirname(here)))
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", default=default_repo)
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    failures, scanned, checked = run_check(args.repo)
    for failure in failures:
        print(format_failure(*failure))
    if failures:
        print(f"{len(failures)} failures in {scanned} files ({checked} citations checked)")
        return 1
    print(f"docs paths: {scanned} files scanned, {checked} citations checked, all exist")
    return 0


if __name__ == "__main__":
    sys.exit(main())
