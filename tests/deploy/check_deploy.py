#!/usr/bin/env python3
"""What can be checked of docker/ without a Docker engine: the Dockerfiles'
bases, apt-get packages (Debian 12 has them), COPY sources, binaries and
runtime libraries; the HAProxy configuration (`haproxy -c`, session hashing,
the grpc.health.v1 check); the compose and Kubernetes files (YAML,
replicas, the balancer, gRPC health checks and probes, drain times).

  check_deploy.py --repo DIR --build-dir DIR               the check
  check_deploy.py --repo DIR --build-dir DIR --self-test   breaks copies of
      docker/ in known ways and fails unless the check reports each one

Prints every problem and exits 1 when there is any."""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import balancer_checks  # noqa: E402
import image_checks  # noqa: E402
import manifest_checks  # noqa: E402

DOCKERFILES = ("Dockerfile", "Dockerfile.gateway", "Dockerfile.balancer")
SERVER_DOCKERFILE = "Dockerfile"


def check_health_probe(image, binary_dir):
    """The server image's HEALTHCHECK is `vpm health`, and the built vpm has it."""
    if image.final.healthcheck[:2] != ["vpm", "health"]:
        return [f"{image.path}: HEALTHCHECK is {image.final.healthcheck}, not `vpm health ...`"]
    vpm = os.path.join(binary_dir, "client", "vpm")
    result = subprocess.run([vpm, "health", "--help"], capture_output=True, text=True,
                            check=False)
    if result.returncode != 0 or "--server" not in result.stdout:
        return [f"{vpm} health --help failed: {result.stdout}{result.stderr}"]
    return []


def run_checks(repo, docker_dir, binary_dir):
    """Every problem found in `docker_dir` (a copy of the repository's
    docker/ in the self-test)."""
    images = [image_checks.Image(os.path.join(docker_dir, name)) for name in DOCKERFILES]
    problems = image_checks.check_apt_packages(images)
    for image in images:
        problems += image_checks.check_bases(image)
        problems += image_checks.check_build_packages_are_the_projects(image, repo)
        problems += image_checks.check_copy_sources(image, repo)
        problems += image_checks.check_copy_from_stages(image, repo, binary_dir)
        problems += image_checks.check_commands(image, repo, binary_dir)
        problems += image_checks.check_runtime_libraries(image, binary_dir)
    problems += check_health_probe(images[DOCKERFILES.index(SERVER_DOCKERFILE)], binary_dir)
    stage_names = {os.path.normpath(i.path): {s.name for s in i.stages} for i in images}
    haproxy = os.path.join(docker_dir, "haproxy.cfg")
    problems += balancer_checks.check_haproxy(haproxy)
    out_ms = balancer_checks.out_of_rotation_ms(haproxy) if os.path.exists(haproxy) else None
    problems += manifest_checks.check_compose(os.path.join(docker_dir, "compose.yaml"),
                                              docker_dir, stage_names, out_ms)
    problems += manifest_checks.check_k8s(os.path.join(docker_dir, "k8s"), out_ms)
    return problems


# (file in docker/, text to replace, replacement, words the report must contain)
BREAKAGES = [
    ("Dockerfile", "libvulkan1 ", "libvulkan-nosuch1 ", "no Debian 12 candidate"),
    ("Dockerfile", "libprotobuf32 ", "", "which the runtime stage does not install"),
    ("Dockerfile", "/src/build/client/vpm-load ", "/src/build/client/vpm-lode ",
     "is not a --target"),
    ("Dockerfile", "COPY shaders/ shaders/", "COPY shader/ shaders/", "not in the repository"),
    ("Dockerfile", "USER 10001:10001", "USER root", "runs as root"),
    ("Dockerfile", '"vpm", "health"', '"vpm", "status"', "not `vpm health"),
    ("Dockerfile.gateway", "FROM debian:12-slim AS gateway", "FROM node:20-slim AS gateway",
     "only"),
    ("Dockerfile.gateway", '"/opt/vpm/client/web/gateway.js"', '"/opt/vpm/client/web/main.js"',
     "no COPY puts"),
    ("Dockerfile.gateway.dockerignore", "!client/web\n", "", "excluded by"),
    ("Dockerfile.balancer", "install -y -q --no-install-recommends haproxy",
     "install -y -q --no-install-recommends haproxy-nosuch", "no Debian 12 candidate"),
    ("Dockerfile.balancer", "COPY docker/haproxy.cfg /etc/haproxy/vpm.cfg",
     "COPY haproxy.cfg /etc/haproxy/vpm.cfg", "not in the repository"),
    ("haproxy.cfg", "balance hdr(x-vpm-session)", "balance hdr(x-session)", "does not hash on"),
    ("haproxy.cfg", "hash-type consistent", "hash-type map-based", "is not consistent"),
    ("haproxy.cfg", "default-server proto h2", "default-server", "needs `proto h2`"),
    ("haproxy.cfg", "bind \"${VPM_BALANCER_LISTEN-:50051}\" proto h2",
     "bind \"${VPM_BALANCER_LISTEN-:50051}\"", "does not speak HTTP/2"),
    ("haproxy.cfg", "436865636b", "436865636c", "is '/grpc.health.v1.Health/Checl'"),
    ("haproxy.cfg", "min-recv 0 binary 00000700000000000100000000020801",
     "min-recv 0 binary 00000700000000000100000000020802", "expects the SERVING answer"),
    ("haproxy.cfg", "timeout check 2s", "timeout check 2s\n    timeout chek 2s", "haproxy -c"),
    ("compose.yaml", '"--drain-s", "5"', '"--drain-s", "2"', "is not longer than"),
    ("compose.yaml", "VPM_SERVERS: vpm-server:50051", "VPM_SERVERS: vpm-servers:50051",
     "VPM_SERVERS"),
    ("compose.yaml", "replicas: 2", "replicas: 1", "fewer than 2 replicas"),
    ("compose.yaml", "target: runtime", "target: runtme", "is not a stage"),
    ("k8s/vpm-server.yaml", "readinessProbe:\n            grpc:", "readinessProbe:\n            tcpSocket:",
     "no gRPC readinessProbe"),
    ("k8s/vpm-server.yaml", "clusterIP: None", "clusterIP: 10.0.0.10", "no headless Service"),
    ("k8s/web-gateway.yaml", "vpm-grpc:50051", "vpm-grpcs:50051", "is not a Service here"),
    ("k8s/vpm-server.yaml", "terminationGracePeriodSeconds: 20",
     "terminationGracePeriodSeconds: 12", "s to stop is not more than"),
    ("k8s/balancer.yaml", "image: vpm-balancer:latest", "image: haproxy:latest",
     "no balancer Deployment"),
]


def self_test(repo, binary_dir):
    """0 when the check passes on docker/ and catches every breakage."""
    source = os.path.join(repo, "docker")
    failures = []
    baseline = run_checks(repo, source, binary_dir)
    if baseline:
        failures.append("the unbroken docker/ already fails:\n  " + "\n  ".join(baseline))
    with tempfile.TemporaryDirectory() as tmp:
        for file, old, new, expected in BREAKAGES:
            copy = os.path.join(tmp, "docker")
            shutil.rmtree(copy, ignore_errors=True)
            shutil.copytree(source, copy)
            path = os.path.join(copy, file)
            with open(path) as f:
                text = f.read()
            if old not in text:
                failures.append(f"{file}: the self-test's text {old!r} is gone; update BREAKAGES")
                continue
            with open(path, "w") as f:
                f.write(text.replace(old, new, 1))
            problems = run_checks(repo, copy, binary_dir)
            if not any(expected in p for p in problems):
                failures.append(f"{file}: {old!r} -> {new!r} went unreported "
                                f"(wanted {expected!r}; got {problems})")
            else:
                print(f"caught: {file}: {old.strip()!r} -> {new.strip()!r}")
    for f in failures:
        print("SELF-TEST FAILURE:", f)
    return 1 if failures else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repo", required=True, help="repository root")
    parser.add_argument("--build-dir", required=True, help="the CMake build tree")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    repo, binary_dir = os.path.abspath(args.repo), os.path.abspath(args.build_dir)
    if args.self_test:
        return self_test(repo, binary_dir)
    problems = run_checks(repo, os.path.join(repo, "docker"), binary_dir)
    for p in problems:
        print("PROBLEM:", p)
    if not problems:
        print("docker/: Dockerfiles, HAProxy, compose and Kubernetes files check out")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
