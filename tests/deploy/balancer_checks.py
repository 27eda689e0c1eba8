"""Checks of docker/haproxy.cfg, the balancer compose and Kubernetes run:
HAProxy itself accepts it (`haproxy -c`), and it has what the scale-out
depends on: gRPC over HTTP/2 on 50051, consistent hashing on x-vpm-session,
the grpc.health.v1 check (grpc_health_probe.py decodes its bytes), replicas
found by DNS under the name vpm-server:50051. Each check returns problems."""

import os
import re
import shlex
import shutil
import subprocess

import grpc_health_probe

SESSION_HEADER = "x-vpm-session"
SERVER_NAME = "vpm-server"
GRPC_PORT = 50051


def parse(path):
    """[(section keyword, name, [token lists of its lines])] of an HAProxy
    config: a line that starts at column 0 opens a section."""
    sections = []
    with open(path) as f:
        for raw in f:
            if not raw.strip() or raw.lstrip().startswith("#"):
                continue
            tokens = shlex.split(raw, comments=True)
            if not tokens:
                continue
            if not raw[0].isspace():
                sections.append((tokens[0], tokens[1] if len(tokens) > 1 else "", []))
            elif sections:
                sections[-1][2].append(tokens)
    return sections


def expand(value):
    """${VAR-default} as HAProxy expands it with VAR unset."""
    return re.sub(r"\$\{\w+-([^}]*)\}", r"\1", value)


def _option(tokens, name, default=None):
    return tokens[tokens.index(name) + 1] if name in tokens[:-1] else default


def _ms(value):
    """HAProxy time (1s, 500ms, 2000) in ms."""
    m = re.fullmatch(r"(\d+)(us|ms|s|m|h|d)?", value or "")
    if not m:
        return None
    scale = {"us": 0.001, "ms": 1, None: 1, "s": 1000, "m": 60000, "h": 3600000, "d": 86400000}
    return int(m.group(1)) * scale[m.group(2)]


def out_of_rotation_ms(path):
    """The longest time, ms, from a replica turning NOT_SERVING to HAProxy
    taking it out: one interval to the next check, fall - 1 more checks at
    fastinter, and the last check's `timeout check`; None when unknown."""
    sections = parse(path)
    backend = _grpc_backend(sections)
    if backend is None:
        return None
    lines = backend[2]
    server = next((t for t in lines if t[0] == "default-server"), [])
    inter = _ms(_option(server, "inter", "2s"))
    fastinter = _ms(_option(server, "fastinter", _option(server, "inter", "2s")))
    fall = int(_option(server, "fall", "3"))
    timeouts = [t for _, _, ls in sections for t in ls if t[:2] == ["timeout", "check"]]
    check = _ms(timeouts[-1][2]) if timeouts else inter
    if None in (inter, fastinter, check):
        return None
    return inter + (fall - 1) * fastinter + check


def _grpc_frontend(sections):
    for kind, name, lines in sections:
        if kind != "frontend":
            continue
        for t in lines:
            if t[0] == "bind" and expand(t[1]).rsplit(":", 1)[-1] == str(GRPC_PORT):
                return kind, name, lines
    return None


def _grpc_backend(sections):
    frontend = _grpc_frontend(sections)
    if frontend is None:
        return None
    target = next((t[1] for t in frontend[2] if t[0] == "default_backend"), None)
    return next((s for s in sections if s[0] == "backend" and s[1] == target), None)


def check_haproxy(path):
    problems = []
    if not os.path.exists(path):
        return [f"{path}: missing"]
    problems += _haproxy_accepts(path)
    sections = parse(path)
    frontend = _grpc_frontend(sections)
    if frontend is None:
        return problems + [f"{path}: no frontend binds port {GRPC_PORT}"]
    binds = [t for t in frontend[2] if t[0] == "bind"]
    if not any(_option(t, "proto") == "h2" for t in binds):
        problems.append(f"{path}: frontend {frontend[1]} does not speak HTTP/2 (bind ... proto h2): "
                        "gRPC needs it")
    backend = _grpc_backend(sections)
    if backend is None:
        return problems + [f"{path}: frontend {frontend[1]} has no default_backend here"]
    name, lines = backend[1], backend[2]
    first = lambda word: next((t for t in lines if t[0] == word), [])  # noqa: E731
    if first("balance")[1:] != [f"hdr({SESSION_HEADER})"]:
        problems.append(f"{path}: backend {name} does not hash on {SESSION_HEADER} "
                        f"(balance {' '.join(first('balance')[1:])})")
    if first("hash-type")[1:2] != ["consistent"]:
        problems.append(f"{path}: backend {name}: hash-type is not consistent (a replica going "
                        "would move every key)")
    if first("hash-balance-factor"):
        problems.append(f"{path}: backend {name}: hash-balance-factor moves keys off a busy "
                        "replica, away from their sessions")
    server = first("default-server")
    if _option(server, "proto") != "h2" or "check" not in server:
        problems.append(f"{path}: backend {name}: default-server needs `proto h2` (gRPC is "
                        f"HTTP/2) and `check` (got {' '.join(server[1:])})")
    problems += _check_health_rules(path, name, lines)
    problems += _check_servers(path, name, lines, sections)
    return problems


def _check_health_rules(path, name, lines):
    if ["option", "tcp-check"] not in lines:
        return [f"{path}: backend {name}: no `option tcp-check` (the grpc.health.v1 check)"]
    sends, expects = [], []
    for t in lines:
        if t[:2] == ["tcp-check", "send-binary"]:
            sends.append(bytes.fromhex(t[2]))
        elif t[:2] == ["tcp-check", "expect"] and "binary" in t:
            expects.append(bytes.fromhex(t[t.index("binary") + 1]))
    return [f"{path}: backend {name}: {p}" for p in grpc_health_probe.problems_of(sends, expects)]


def _check_servers(path, name, lines, sections):
    templates = [t for t in lines if t[0] == "server-template"]
    if len(templates) != 1:
        return [f"{path}: backend {name}: {len(templates)} server-template lines, expected one "
                "(tests/balancer replaces it with the loopback replicas)"]
    t = templates[0]
    problems = []
    if expand(t[3]) != f"{SERVER_NAME}:{GRPC_PORT}":
        problems.append(f"{path}: server-template finds {expand(t[3])}, expected the DNS name "
                        f"{SERVER_NAME}:{GRPC_PORT} (every replica behind one name)")
    resolvers = _option(t, "resolvers")
    if resolvers is None or not any(s[0] == "resolvers" and s[1] == resolvers for s in sections):
        problems.append(f"{path}: server-template has no resolvers section ({resolvers})")
    return problems


def _haproxy_accepts(path):
    haproxy = shutil.which("haproxy")
    if haproxy is None:
        return ["haproxy is not installed (scripts/install-deps.sh): cannot check "
                f"{path} with `haproxy -c`"]
    result = subprocess.run([haproxy, "-c", "-f", path], capture_output=True, text=True,
                            check=False)
    if result.returncode != 0:
        return [f"{path}: haproxy -c: {result.stdout}{result.stderr}".strip()]
    return []


def check_drain(where, args, stop_s, out_ms):
    """vpm-server's `args` drain longer than the balancer needs to take a
    replica out (`out_ms`), and the orchestrator's stop period (`stop_s`)
    covers drain + grace."""
    drain = float(_option(args, "--drain-s", "0"))
    grace = float(_option(args, "--shutdown-grace-s", "5"))
    problems = []
    if out_ms is not None and drain * 1000 <= out_ms:
        problems.append(f"{where}: --drain-s {drain:g} is not longer than the {out_ms} ms the "
                        "balancer may take to see NOT_SERVING: the replica would stop in rotation")
    if stop_s is not None and stop_s <= drain + grace:
        problems.append(f"{where}: {stop_s} s to stop is not more than --drain-s {drain:g} + "
                        f"--shutdown-grace-s {grace:g}")
    return problems
