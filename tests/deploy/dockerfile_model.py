"""A Dockerfile read into stages, enough to check what an image names
without a Docker engine: base images, apt-get packages, COPY sources and
destinations, WORKDIRs, RUN lines, USER, and the exec-form ENTRYPOINT, CMD
and HEALTHCHECK of each stage. Also the .dockerignore rules of a build
context, to tell whether a COPY source reaches the build."""

import fnmatch
import json
import posixpath
import re
import shlex
from dataclasses import dataclass, field


@dataclass
class Copy:
    sources: list  # paths in the build context, or in stage `from_stage`
    dest: str      # absolute path in the image
    from_stage: str = ""


@dataclass
class Stage:
    name: str
    base: str
    apt_packages: list = field(default_factory=list)
    copies: list = field(default_factory=list)
    runs: list = field(default_factory=list)     # (workdir, command line)
    workdir: str = "/"
    user: str = ""
    entrypoint: list = field(default_factory=list)
    cmd: list = field(default_factory=list)
    healthcheck: list = field(default_factory=list)

    def resolve(self, path):
        """`path` in this stage as an absolute path (relative to WORKDIR)."""
        return posixpath.normpath(posixpath.join(self.workdir, path))


def _logical_lines(text):
    """Instructions with their continuation lines joined; comments dropped."""
    lines, current = [], ""
    for raw in text.splitlines():
        stripped = raw.strip()
        if not current and (not stripped or stripped.startswith("#")):
            continue
        if stripped.startswith("#"):
            continue  # a comment inside a continued instruction
        if stripped.endswith("\\"):
            current += stripped[:-1] + " "
            continue
        lines.append(current + stripped)
        current = ""
    if current:
        lines.append(current)
    return lines


def _apt_packages(run_line):
    """Package names after every `apt-get install` in a RUN line."""
    packages = []
    for command in re.split(r"&&|;|\|\|?", run_line):
        words = shlex.split(command)
        # Environment assignments (DEBIAN_FRONTEND=...) may come first.
        while words and re.match(r"^[A-Z_]+=", words[0]):
            words.pop(0)
        if len(words) >= 2 and words[0] == "apt-get" and "install" in words:
            after = words[words.index("install") + 1:]
            packages += [w for w in after if not w.startswith("-")]
    return packages


def _exec_form(text, instruction):
    text = text.strip()
    if not text.startswith("["):
        raise ValueError(f"{instruction} {text!r}: use the exec (JSON) form")
    return json.loads(text)


def parse_dockerfile(text):
    """The stages of a Dockerfile, in order."""
    stages = []
    for line in _logical_lines(text):
        instruction, _, rest = line.partition(" ")
        instruction = instruction.upper()
        if instruction == "FROM":
            words = rest.split()
            name = words[2] if len(words) >= 3 and words[1].upper() == "AS" else ""
            stages.append(Stage(name=name, base=words[0]))
            continue
        if not stages:
            continue  # ARG or a parser directive before the first FROM
        stage = stages[-1]
        if instruction == "RUN":
            stage.runs.append((stage.workdir, rest))
            stage.apt_packages += _apt_packages(rest)
        elif instruction == "COPY":
            words = shlex.split(rest)
            flags = [w for w in words if w.startswith("--")]
            paths = [w for w in words if not w.startswith("--")]
            from_stage = next((f.split("=", 1)[1] for f in flags if f.startswith("--from=")), "")
            stage.copies.append(Copy(paths[:-1], stage.resolve(paths[-1]), from_stage))
        elif instruction == "WORKDIR":
            stage.workdir = stage.resolve(rest.strip())
        elif instruction == "USER":
            stage.user = rest.strip()
        elif instruction == "ENTRYPOINT":
            stage.entrypoint = _exec_form(rest, instruction)
        elif instruction == "CMD":
            stage.cmd = _exec_form(rest, instruction)
        elif instruction == "HEALTHCHECK":
            words = rest.split(" CMD ", 1)
            if len(words) != 2:
                raise ValueError(f"HEALTHCHECK {rest!r}: expected HEALTHCHECK [options] CMD [...]")
            stage.healthcheck = _exec_form(words[1], instruction)
    return stages


def parse_dockerignore(text):
    """(pattern, excluded) rules in order; the last matching rule wins."""
    rules = []
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        negated = line.startswith("!")
        pattern = line[1:] if negated else line
        rules.append((pattern.strip("/"), not negated))
    return rules


def _matches(pattern, path):
    """Whether `pattern` matches `path` or one of its parent folders."""
    parts = path.split("/")
    prefixes = ["/".join(parts[:i]) for i in range(1, len(parts) + 1)]
    if pattern.startswith("**/"):
        tail = pattern[3:]
        return any(fnmatch.fnmatchcase(p.split("/")[-1], tail) or
                   fnmatch.fnmatchcase(p, tail) for p in prefixes)
    return any(fnmatch.fnmatchcase(p, pattern) and p.count("/") == pattern.count("/")
               for p in prefixes)


def is_ignored(rules, path):
    """Whether the build context leaves out `path` (relative, no leading /).
    A folder that is itself excluded can still have files brought back by a
    later `!` rule, as in Docker."""
    excluded = False
    for pattern, excludes in rules:
        if _matches(pattern, path):
            excluded = excludes
    return excluded
