"""Checks of docker/Dockerfile*: what each image installs, copies and runs
must exist, without building it. Each check returns a list of problems
(strings); empty means it holds."""

import os
import re
import subprocess

from dockerfile_model import is_ignored, parse_dockerfile, parse_dockerignore

ALLOWED_BASES = {"debian:12", "debian:12-slim"}
# Packages every debian:12-slim image has (Essential, or needed by apt and
# dpkg themselves): shared libraries from them need no apt-get line.
BASE_IMAGE_PACKAGES = {"libc6", "libgcc-s1", "libstdc++6", "zlib1g", "liblzma5"}
# Opened with dlopen, so ldd does not list it: a server image needs them.
VULKAN_RUNTIME = {"libvulkan1", "mesa-vulkan-drivers"}
PATH_DIRS = ("/usr/local/bin", "/usr/bin", "/bin", "/usr/sbin", "/sbin")


class Image:
    """One Dockerfile with its stages and its .dockerignore."""

    def __init__(self, dockerfile):
        self.path = dockerfile
        with open(dockerfile) as f:
            self.stages = parse_dockerfile(f.read())
        ignore = dockerfile + ".dockerignore"
        self.ignore_path = ignore if os.path.exists(ignore) else None
        self.ignore_rules = []
        if self.ignore_path:
            with open(ignore) as f:
                self.ignore_rules = parse_dockerignore(f.read())

    def stage(self, name):
        return next((s for s in self.stages if s.name == name), None)

    @property
    def final(self):
        return self.stages[-1]


# apt-cache's answers, kept for the process: the self-test asks about the
# same packages once per broken copy, and each call costs most of a second.
_CANDIDATES = {}


def debian12_candidates(packages):
    """{name: True when apt knows a Debian 12 (bookworm) version of it}.
    One `apt-cache policy` call for the names not asked about before; names
    it does not know are absent."""
    unknown = sorted(set(packages) - set(_CANDIDATES))
    if unknown:
        for name in unknown:
            _CANDIDATES[name] = None  # not known to apt unless listed below
        _CANDIDATES.update(_apt_policy(unknown))
    return {p: _CANDIDATES[p] for p in packages if _CANDIDATES[p] is not None}


def _apt_policy(packages):
    result = subprocess.run(["apt-cache", "policy", *packages],
                            capture_output=True, text=True, check=False)
    found, name, candidate = {}, None, None
    for line in result.stdout.splitlines():
        if re.match(r"^\S.*:$", line):
            name, candidate = line[:-1], None
            found[name] = False
        elif name and line.strip().startswith("Candidate:"):
            candidate = line.split(":", 1)[1].strip()
        elif name and candidate not in (None, "(none)") and re.search(r"\sbookworm(-\w+)?/", line):
            found[name] = True
    return found


def check_bases(image):
    problems = []
    names = set()
    for s in image.stages:
        if s.base not in ALLOWED_BASES and s.base not in names:
            problems.append(f"{image.path}: FROM {s.base}: only {sorted(ALLOWED_BASES)} "
                            "or an earlier stage")
        names.add(s.name)
    return problems


def check_apt_packages(images):
    wanted = {p: img.path for img in images for s in img.stages for p in s.apt_packages}
    if not wanted:
        return ["no apt-get install line in any Dockerfile"]
    known = debian12_candidates(wanted)
    if not any(known.values()):
        return ["apt-cache knows no Debian 12 package (empty package lists? run apt-get update)"]
    return [f"{path}: apt-get package {p!r} has no Debian 12 candidate (apt-cache policy {p})"
            for p, path in sorted(wanted.items()) if not known.get(p)]


def install_deps_packages(repo):
    """The package names scripts/install-deps.sh lists in its `packages=(`
    and `packages+=(` arrays (one `)` line closes an array)."""
    with open(os.path.join(repo, "scripts/install-deps.sh")) as f:
        lines = f.read().splitlines()
    names, inside = set(), False
    for line in lines:
        code = line.split("#", 1)[0]
        if re.match(r"\s*packages\+?=\(", code):
            inside = True
            code = code.split("(", 1)[1]
        if inside:
            inside = ")" not in code
            names.update(code.split(")", 1)[0].split())
    return names


def check_build_packages_are_the_projects(image, repo):
    """A build stage installs only what scripts/install-deps.sh installs:
    the image builds with the same dependencies as a developer machine."""
    allowed = install_deps_packages(repo)
    problems = []
    for s in image.stages:
        if any("cmake" in run for _, run in s.runs):
            problems += [f"{image.path}: stage {s.name}: {p!r} is not in scripts/install-deps.sh"
                         for p in s.apt_packages if p not in allowed]
    return problems


def executable_targets(repo):
    """Names of every add_executable in the repository's CMakeLists."""
    names = set()
    for root, dirs, files in os.walk(repo):
        dirs[:] = [d for d in dirs if not d.startswith((".", "build")) and d != "node_modules"]
        if "CMakeLists.txt" in files:
            with open(os.path.join(root, "CMakeLists.txt")) as f:
                names.update(re.findall(r"add_executable\(\s*([\w.-]+)", f.read()))
    return names


def built_targets(stage):
    """(build folder in the image, targets) of each `cmake --build` RUN."""
    built = []
    for workdir, run in stage.runs:
        m = re.search(r"cmake --build (\S+) --target ((?:[\w.-]+ ?)+)", run)
        if m:
            built.append((os.path.join(workdir, m.group(1)), m.group(2).split()))
    return built


def check_copy_from_stages(image, repo, binary_dir):
    """COPY --from=STAGE sources: binaries that stage's cmake builds (and
    that exist in this build tree at the same relative path, so the path is
    the one CMake writes), or node_modules where that stage ran npm ci."""
    problems, targets = [], executable_targets(repo)
    for s in image.stages:
        for copy in s.copies:
            if not copy.from_stage:
                continue
            source_stage = image.stage(copy.from_stage)
            if source_stage is None:
                problems.append(f"{image.path}: COPY --from={copy.from_stage}: no such stage")
                continue
            npm_dirs = {os.path.join(w, "node_modules") for w, run in source_stage.runs
                        if "npm ci" in run}
            for source in copy.sources:
                if source in npm_dirs:
                    continue
                problems += _check_built_binary(image, source_stage, source, targets, binary_dir)
    return problems


def _check_built_binary(image, stage, source, targets, binary_dir):
    for build_dir, built in built_targets(stage):
        if not source.startswith(build_dir + "/"):
            continue
        name, relative = os.path.basename(source), os.path.relpath(source, build_dir)
        problems = []
        if name not in built:
            problems.append(f"{image.path}: COPY {source}: {name} is not a --target of "
                            f"stage {stage.name}'s cmake --build")
        if name not in targets:
            problems.append(f"{image.path}: COPY {source}: no add_executable({name}) in the project")
        local = os.path.join(binary_dir, relative)
        if not os.access(local, os.X_OK):
            problems.append(f"{image.path}: COPY {source}: the project builds no {relative} "
                            f"(not in {binary_dir})")
        return problems
    return [f"{image.path}: COPY --from={stage.name} {source}: that stage makes no such path"]


def check_copy_sources(image, repo):
    """COPY sources from the build context exist and are not left out of it."""
    problems = []
    if image.ignore_path is None:
        problems.append(f"{image.path}: no {os.path.basename(image.path)}.dockerignore beside it")
    for s in image.stages:
        for copy in s.copies:
            if copy.from_stage:
                continue
            for source in copy.sources:
                relative = source.strip("/").removeprefix("./") or "."
                if not os.path.exists(os.path.join(repo, relative)):
                    problems.append(f"{image.path}: COPY {source}: not in the repository")
                elif relative != "." and is_ignored(image.ignore_rules, relative):
                    problems.append(f"{image.path}: COPY {source}: excluded by {image.ignore_path}")
    return problems


_PACKAGE_OF = {}


def _path_variants(path):
    """`path` and its /usr-merged twins, as dpkg may have registered any."""
    variants = {path, os.path.realpath(path)}
    for p in list(variants):
        variants.add(p[4:] if p.startswith("/usr/") else "/usr" + p)
    return variants


def prefetch_packages(paths):
    """Asks dpkg once about many paths (one call per path is slow)."""
    variants = {v for p in paths for v in _path_variants(p)} - set(_PACKAGE_OF)
    if not variants:
        return
    result = subprocess.run(["dpkg", "-S", *sorted(variants)], capture_output=True, text=True,
                            check=False)
    for line in result.stdout.splitlines():
        owners, _, owned = line.partition(": ")
        if not owners.startswith("diversion"):
            # "libpng16-16:amd64: /usr/lib/..." names the package with its architecture.
            _PACKAGE_OF[owned.strip()] = owners.split(",")[0].strip().split(":")[0]
    for v in variants:
        _PACKAGE_OF.setdefault(v, None)


def package_of(path):
    """The Debian package that installed `path` here, or None."""
    prefetch_packages([path])
    return next((_PACKAGE_OF[v] for v in sorted(_path_variants(path)) if _PACKAGE_OF.get(v)),
                None)


def image_path_to_repo(stage, image_path, repo):
    """The repository file a COPY put at `image_path`, or None."""
    for copy in stage.copies:
        if copy.from_stage:
            continue
        for source in copy.sources:
            local = os.path.join(repo, source.strip("/"))
            if os.path.isdir(local) and image_path.startswith(copy.dest + "/"):
                return os.path.join(local, os.path.relpath(image_path, copy.dest))
            if os.path.isfile(local) and image_path in (copy.dest, os.path.join(
                    copy.dest, os.path.basename(source))):
                return local
    return None


def check_commands(image, repo, binary_dir):
    """Programs that ENTRYPOINT, CMD and HEALTHCHECK start are in the final
    image (copied into the PATH from the build, or from an installed
    package), and absolute file arguments come from the repository."""
    s, problems = image.final, []
    copied = {os.path.basename(c.dest): c for c in s.copies
              if c.from_stage and os.path.dirname(c.dest) in PATH_DIRS}
    for what, argv in (("ENTRYPOINT", s.entrypoint), ("HEALTHCHECK", s.healthcheck),
                       ("CMD", s.cmd if not s.entrypoint else [])):
        if not argv:
            continue
        program = argv[0]
        if program not in copied:
            owner = next((package_of(os.path.join(d, program)) for d in PATH_DIRS
                          if package_of(os.path.join(d, program))), None)
            if owner is None or owner not in s.apt_packages:
                problems.append(f"{image.path}: {what} runs {program!r}: neither copied into "
                                f"the PATH nor installed by an apt-get line of stage {s.name}")
        for arg in argv[1:]:
            if arg.startswith("/") and not arg.startswith("/data"):
                local = image_path_to_repo(s, arg, repo)
                if local is None or not os.path.exists(local):
                    problems.append(f"{image.path}: {what} names {arg}: no COPY puts a "
                                    "repository file there")
    if not s.user or s.user.split(":")[0] in ("root", "0"):
        problems.append(f"{image.path}: the final stage runs as root (USER {s.user or 'unset'})")
    return problems


def check_runtime_libraries(image, binary_dir):
    """Every shared library of the binaries the final stage copies from a
    build comes from a package that stage installs (or the base image)."""
    s, problems = image.final, []
    installed = set(s.apt_packages) | BASE_IMAGE_PACKAGES
    binaries = [c for c in s.copies if c.from_stage and os.path.dirname(c.dest) in PATH_DIRS]
    for copy in binaries:
        build_stage = image.stage(copy.from_stage)
        for build_dir, _ in built_targets(build_stage):
            for source in copy.sources:
                if source.startswith(build_dir + "/"):
                    local = os.path.join(binary_dir, os.path.relpath(source, build_dir))
                    problems += _check_libraries_of(image, local, installed)
    if binaries and not VULKAN_RUNTIME <= installed:
        problems.append(f"{image.path}: the runtime lacks {sorted(VULKAN_RUNTIME - installed)} "
                        "(the Vulkan loader and lavapipe)")
    return problems


_LIBRARIES = {}  # binary -> the shared libraries ldd resolves (built once per run)


def _libraries_of(binary):
    if binary not in _LIBRARIES:
        ldd = subprocess.run(["ldd", binary], capture_output=True, text=True, check=False)
        _LIBRARIES[binary] = re.findall(r"=>\s+(/\S+)", ldd.stdout)
    return _LIBRARIES[binary]


def _check_libraries_of(image, binary, installed):
    if not os.path.exists(binary):
        return []  # reported by check_copy_from_stages
    libraries = _libraries_of(binary)
    prefetch_packages(libraries)
    missing = {}  # package (or None: no package) -> libraries
    for lib in libraries:
        owner = package_of(lib)
        if owner not in installed:
            missing.setdefault(owner, []).append(os.path.basename(lib))
    name = os.path.basename(binary)
    return [f"{image.path}: {name} needs {', '.join(libs)}, " +
            (f"from {owner}, which the runtime stage does not install" if owner else
             "which no Debian package provides here")
            for owner, libs in sorted(missing.items(), key=lambda kv: str(kv[0]))]
