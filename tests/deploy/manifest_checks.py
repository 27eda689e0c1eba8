"""Checks of docker/compose.yaml and docker/k8s/*.yaml: they parse as YAML
and have the structure the scale-out depends on (two server replicas behind
the HAProxy balancer built from docker/Dockerfile.balancer, gRPC health
checks and probes, a drain longer than the balancer takes to notice it,
names that refer to each other). docker/haproxy.cfg itself:
balancer_checks.py. Each check returns problems."""

import glob
import os

import yaml

from balancer_checks import check_drain

SERVER_NAME = "vpm-server"  # compose service, k8s headless Service, the balancer's DNS name
GRPC_PORT = 50051
BALANCER_DOCKERFILE = "Dockerfile.balancer"


def load(path):
    with open(path) as f:
        return yaml.safe_load(f)


def load_all(path):
    with open(path) as f:
        return [d for d in yaml.safe_load_all(f) if d is not None]


def _listen_port(args):
    """The port of `--listen HOST:PORT` in an argument list, or None."""
    if "--listen" in args and args.index("--listen") + 1 < len(args):
        return int(args[args.index("--listen") + 1].rsplit(":", 1)[1])
    return None


def _server_target(args):
    """(host, port) of `--server HOST:PORT` in an argument list, or None."""
    if "--server" in args and args.index("--server") + 1 < len(args):
        host, port = args[args.index("--server") + 1].rsplit(":", 1)
        return host, int(port)
    return None


def _built_from(service, dockerfile):
    return str(service.get("build", {}).get("dockerfile", "")).endswith(dockerfile)


def check_compose(path, docker_dir, stage_names, out_ms):
    """`stage_names`: {Dockerfile path: set of its stage names}; `out_ms`:
    how long the balancer may take to take a draining replica out."""
    compose, problems = load(path), []
    services = compose.get("services", {})
    server = services.get(SERVER_NAME)
    if server is None:
        return [f"{path}: no {SERVER_NAME} service"]
    if int(server.get("deploy", {}).get("replicas", 1)) < 2:
        problems.append(f"{path}: {SERVER_NAME} has fewer than 2 replicas")
    if "ports" in server:
        problems.append(f"{path}: {SERVER_NAME} publishes ports: clients must come through the "
                        "balancer")
    if server.get("healthcheck", {}).get("test", [None, None, None])[1:3] != ["vpm", "health"]:
        problems.append(f"{path}: {SERVER_NAME}'s healthcheck is not `vpm health`")
    if _listen_port(server.get("command", [])) != GRPC_PORT:
        problems.append(f"{path}: {SERVER_NAME} does not --listen on {GRPC_PORT}")
    stop = server.get("stop_grace_period")
    stop_s = float(str(stop).rstrip("s")) if stop is not None else 10.0
    problems += check_drain(f"{path}: {SERVER_NAME}", server.get("command", []), stop_s, out_ms)
    for name, service in services.items():
        problems += _check_build(path, docker_dir, name, service, stage_names)
        for volume in service.get("volumes", []):
            host = volume.split(":", 1)[0]
            if host.startswith("./") and not os.path.exists(os.path.join(docker_dir, host)):
                problems.append(f"{path}: {name} mounts {host}, which does not exist")
    balancers = [n for n, s in services.items() if _built_from(s, BALANCER_DOCKERFILE)]
    if not balancers:
        problems.append(f"{path}: no balancer service (built from {BALANCER_DOCKERFILE})")
    for name in balancers:
        servers = services[name].get("environment", {}).get("VPM_SERVERS")
        if servers != f"{SERVER_NAME}:{GRPC_PORT}":
            problems.append(f"{path}: {name}: VPM_SERVERS is {servers!r}, not the service "
                            f"{SERVER_NAME}:{GRPC_PORT}")
    gateways = [(n, s) for n, s in services.items() if "Dockerfile.gateway" in
                str(s.get("build", {}).get("dockerfile", ""))]
    if not gateways:
        problems.append(f"{path}: no web gateway service (built from Dockerfile.gateway)")
    for name, gateway in gateways:
        target = _server_target(gateway.get("command", []))
        if target is None or target[0] not in balancers or target[1] != GRPC_PORT:
            problems.append(f"{path}: {name} --server {target} is not the balancer's {GRPC_PORT}")
    return problems


def _check_build(path, docker_dir, name, service, stage_names):
    build = service.get("build")
    if build is None:
        return []
    context = os.path.normpath(os.path.join(docker_dir, build.get("context", ".")))
    dockerfile = os.path.normpath(os.path.join(context, build.get("dockerfile", "Dockerfile")))
    if dockerfile not in stage_names:
        return [f"{path}: {name} builds {dockerfile}, which is not a checked Dockerfile"]
    if build.get("target") and build["target"] not in stage_names[dockerfile]:
        return [f"{path}: {name}: target {build['target']!r} is not a stage of {dockerfile}"]
    return []


def _containers(doc):
    return doc.get("spec", {}).get("template", {}).get("spec", {}).get("containers", [])


def _port_number(container, port):
    """A probe's port (a number or a container port's name) as a number."""
    if isinstance(port, int):
        return port
    return next((p["containerPort"] for p in container.get("ports", []) if p.get("name") == port),
                None)


def check_k8s(k8s_dir, out_ms):
    docs, problems = [], []
    for path in sorted(glob.glob(os.path.join(k8s_dir, "*.yaml"))):
        docs += [(path, d) for d in load_all(path)]
    if not docs:
        return [f"{k8s_dir}: no manifests"]
    for path, d in docs:
        if "apiVersion" not in d or "kind" not in d or "name" not in d.get("metadata", {}):
            problems.append(f"{path}: a document without apiVersion, kind or metadata.name")
    services = {d["metadata"]["name"]: d for _, d in docs if d.get("kind") == "Service"}
    workloads = [(p, d) for p, d in docs if d.get("kind") in ("Deployment", "StatefulSet")]
    servers = [(p, d) for p, d in workloads if d["metadata"]["name"] == SERVER_NAME]
    if not servers:
        return problems + [f"{k8s_dir}: no {SERVER_NAME} Deployment or StatefulSet"]
    for path, server in servers:
        problems += _check_server_workload(path, server, services, out_ms)
    balancers = [(p, d) for p, d in workloads for c in _containers(d)
                 if "vpm-balancer" in c.get("image", "")]
    if not balancers:
        problems.append(f"{k8s_dir}: no balancer Deployment (image vpm-balancer)")
    for path, balancer in balancers:
        problems += _check_balancer_workload(path, balancer, services)
    gateway_args = [c.get("args", []) for _, d in workloads for c in _containers(d)
                    if "vpm-web" in c.get("image", "")]
    if not gateway_args:
        problems.append(f"{k8s_dir}: no web gateway Deployment (image vpm-web)")
    for args in gateway_args:
        target = _server_target(args)
        if target is None or target[0] not in services:
            problems.append(f"{k8s_dir}: the gateway's --server {target} is not a Service here")
    return problems


def _check_balancer_workload(path, balancer, services):
    problems = []
    for container in _containers(balancer):
        env = {e["name"]: e.get("value", "") for e in container.get("env", [])}
        servers = env.get("VPM_SERVERS", "")
        if not servers.startswith(f"{SERVER_NAME}.") or not servers.endswith(f":{GRPC_PORT}"):
            problems.append(f"{path}: VPM_SERVERS {servers!r} is not the headless Service "
                            f"{SERVER_NAME}.NAMESPACE...:{GRPC_PORT}")
    labels = balancer["spec"]["template"]["metadata"].get("labels", {})
    fronts = [s for s in services.values()
              if s["spec"].get("selector") and not s["spec"]["selector"].items() - labels.items()
              and any(p.get("port") == GRPC_PORT for p in s["spec"].get("ports", []))]
    if not fronts:
        problems.append(f"{path}: no Service on {GRPC_PORT} selects the balancer pods")
    return problems


def _check_server_workload(path, server, services, out_ms):
    problems = []
    if int(server["spec"].get("replicas", 1)) < 2:
        problems.append(f"{path}: {SERVER_NAME} has fewer than 2 replicas")
    for container in _containers(server):
        if _listen_port(container.get("args", [])) != GRPC_PORT:
            problems.append(f"{path}: {container['name']} does not --listen on {GRPC_PORT}")
        stop_s = server["spec"]["template"]["spec"].get("terminationGracePeriodSeconds", 30)
        problems += check_drain(f"{path}: {container['name']}", container.get("args", []),
                                stop_s, out_ms)
        for probe in ("readinessProbe", "livenessProbe"):
            grpc = container.get(probe, {}).get("grpc")
            if grpc is None:
                problems.append(f"{path}: {container['name']} has no gRPC {probe}")
            elif _port_number(container, grpc.get("port")) != GRPC_PORT:
                problems.append(f"{path}: {container['name']} {probe} is not on {GRPC_PORT}")
    headless = services.get(SERVER_NAME)
    if headless is None or headless["spec"].get("clusterIP") != "None":
        problems.append(f"{path}: no headless Service {SERVER_NAME} (clusterIP: None) for "
                        "the balancer to find every replica")
    elif headless["spec"].get("selector", {}).items() - \
            server["spec"]["template"]["metadata"].get("labels", {}).items():
        problems.append(f"{path}: Service {SERVER_NAME} does not select the server pods")
    return problems
