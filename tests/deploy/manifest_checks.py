"""Checks of docker/compose.yaml, docker/envoy.yaml and docker/k8s/*.yaml:
they parse as YAML and have the structure the scale-out depends on (two
server replicas, session hashing on x-vpm-session, gRPC health checks and
probes, names that refer to each other). Each check returns problems."""

import glob
import os

import yaml

SESSION_HEADER = "x-vpm-session"
SERVER_NAME = "vpm-server"  # compose service, k8s headless Service, Envoy upstream
GRPC_PORT = 50051


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


def envoy_upstreams(envoy):
    """{cluster name: cluster} of Envoy's static clusters."""
    return {c["name"]: c for c in envoy.get("static_resources", {}).get("clusters", [])}


def check_envoy(path):
    envoy, problems = load(path), []
    clusters = envoy_upstreams(envoy)
    listeners = envoy.get("static_resources", {}).get("listeners", [])
    ports = [l["address"]["socket_address"]["port_value"] for l in listeners]
    if GRPC_PORT not in ports:
        problems.append(f"{path}: no listener on {GRPC_PORT} (listeners on {ports})")
    routes = [r for l in listeners for fc in l.get("filter_chains", [])
              for f in fc.get("filters", [])
              for vh in f.get("typed_config", {}).get("route_config", {}).get("virtual_hosts", [])
              for r in vh.get("routes", [])]
    if not routes:
        problems.append(f"{path}: no routes")
    for route in routes:
        target = route.get("route", {})
        headers = [h.get("header", {}).get("header_name") for h in target.get("hash_policy", [])]
        if SESSION_HEADER not in headers:
            problems.append(f"{path}: route {route.get('match')} does not hash on {SESSION_HEADER}")
        cluster = clusters.get(target.get("cluster"))
        if cluster is None:
            problems.append(f"{path}: route to unknown cluster {target.get('cluster')!r}")
            continue
        problems += _check_cluster(path, cluster)
    return problems


def _check_cluster(path, cluster):
    problems, name = [], cluster["name"]
    if cluster.get("lb_policy") not in ("RING_HASH", "MAGLEV"):
        problems.append(f"{path}: cluster {name}: lb_policy {cluster.get('lb_policy')} does not "
                        "hash consistently (RING_HASH or MAGLEV)")
    if not any("grpc_health_check" in h for h in cluster.get("health_checks", [])):
        problems.append(f"{path}: cluster {name}: no grpc_health_check")
    options = cluster.get("typed_extension_protocol_options", {})
    if "http2_protocol_options" not in str(options):
        problems.append(f"{path}: cluster {name}: upstream is not HTTP/2 (gRPC needs it)")
    addresses = [e["endpoint"]["address"]["socket_address"]
                 for group in cluster.get("load_assignment", {}).get("endpoints", [])
                 for e in group.get("lb_endpoints", [])]
    if {(a["address"], a["port_value"]) for a in addresses} != {(SERVER_NAME, GRPC_PORT)}:
        problems.append(f"{path}: cluster {name}: endpoints {addresses}, expected the DNS name "
                        f"{SERVER_NAME}:{GRPC_PORT} (every replica behind one name)")
    return problems


def check_compose(path, docker_dir, stage_names):
    """`stage_names`: {Dockerfile path: set of its stage names}."""
    compose, problems = load(path), []
    services = compose.get("services", {})
    server = services.get(SERVER_NAME)
    if server is None:
        return [f"{path}: no {SERVER_NAME} service"]
    if int(server.get("deploy", {}).get("replicas", 1)) < 2:
        problems.append(f"{path}: {SERVER_NAME} has fewer than 2 replicas")
    if "ports" in server:
        problems.append(f"{path}: {SERVER_NAME} publishes ports: clients must come through Envoy")
    if server.get("healthcheck", {}).get("test", [None, None, None])[1:3] != ["vpm", "health"]:
        problems.append(f"{path}: {SERVER_NAME}'s healthcheck is not `vpm health`")
    if _listen_port(server.get("command", [])) != GRPC_PORT:
        problems.append(f"{path}: {SERVER_NAME} does not --listen on {GRPC_PORT}")
    for name, service in services.items():
        problems += _check_build(path, docker_dir, name, service, stage_names)
        for volume in service.get("volumes", []):
            host = volume.split(":", 1)[0]
            if host.startswith("./") and not os.path.exists(os.path.join(docker_dir, host)):
                problems.append(f"{path}: {name} mounts {host}, which does not exist")
    envoys = [n for n, s in services.items() if "envoy" in s.get("image", "")]
    if not envoys:
        problems.append(f"{path}: no Envoy service")
    gateways = [(n, s) for n, s in services.items() if "Dockerfile.gateway" in
                str(s.get("build", {}).get("dockerfile", ""))]
    if not gateways:
        problems.append(f"{path}: no web gateway service (built from Dockerfile.gateway)")
    for name, gateway in gateways:
        target = _server_target(gateway.get("command", []))
        if target is None or target[0] not in envoys or target[1] != GRPC_PORT:
            problems.append(f"{path}: {name} --server {target} is not Envoy's {GRPC_PORT}")
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


def check_k8s(k8s_dir):
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
        problems += _check_server_workload(path, server, services)
    gateway_args = [c.get("args", []) for _, d in workloads for c in _containers(d)
                    if "vpm-web" in c.get("image", "")]
    if not gateway_args:
        problems.append(f"{k8s_dir}: no web gateway Deployment (image vpm-web)")
    for args in gateway_args:
        target = _server_target(args)
        if target is None or target[0] not in services:
            problems.append(f"{k8s_dir}: the gateway's --server {target} is not a Service here")
    return problems


def _check_server_workload(path, server, services):
    problems = []
    if int(server["spec"].get("replicas", 1)) < 2:
        problems.append(f"{path}: {SERVER_NAME} has fewer than 2 replicas")
    for container in _containers(server):
        if _listen_port(container.get("args", [])) != GRPC_PORT:
            problems.append(f"{path}: {container['name']} does not --listen on {GRPC_PORT}")
        for probe in ("readinessProbe", "livenessProbe"):
            grpc = container.get(probe, {}).get("grpc")
            if grpc is None:
                problems.append(f"{path}: {container['name']} has no gRPC {probe}")
            elif _port_number(container, grpc.get("port")) != GRPC_PORT:
                problems.append(f"{path}: {container['name']} {probe} is not on {GRPC_PORT}")
    headless = services.get(SERVER_NAME)
    if headless is None or headless["spec"].get("clusterIP") != "None":
        problems.append(f"{path}: no headless Service {SERVER_NAME} (clusterIP: None) for "
                        "Envoy to find every replica")
    elif headless["spec"].get("selector", {}).items() - \
            server["spec"]["template"]["metadata"].get("labels", {}).items():
        problems.append(f"{path}: Service {SERVER_NAME} does not select the server pods")
    return problems
