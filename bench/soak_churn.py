#!/usr/bin/env python3
"""The churn soak (bench/soak.sh --churn MINUTES; a benchmark, not a test).

One vpm-server on loopback with a users file of 16 users, driven for
MINUTES by 16 client loops, one per user, each a sequence of `vpm`
processes:
  - 12 planners: `vpm play` of a short drag script on a fresh session
    (opened and closed by play), over and over; every fourth play is
    interrupted with SIGINT halfway (a cancelled stream);
  - 1 uploader: `vpm volume upload` of a NIfTI file, then `volume delete`;
  - 1 watcher: opens a session, starts `vpm watch` and kills it with
    SIGKILL after 1-3 s, closes the session;
  - 1 hammer: `vpm snapshot` in a tight loop, one in three with a 5 ms
    deadline (DEADLINE_EXCEEDED expected);
  - 1 pair baseline: before the churn, 2 planners alone for 20 s give the
    reference frame rate.
Prints: unexpected errors (goal 0), aggregate fps of the planners against
the 2-session baseline, p50/p99 event-to-frame latency per planner, and the
server's RSS, threads and open file descriptors before the churn, at its
start (a tenth in, warm), middle and end, and idle after it (goal: start,
middle and end flat within 10%).

usage: bench/soak.sh --churn MINUTES [BUILD_DIR] [SOURCE]
       (soak_churn.py BUILD_DIR MINUTES [SOURCE])
"""
import json, os, random, signal, subprocess, sys, tempfile, threading, time

build, minutes = sys.argv[1], float(sys.argv[2])
source = sys.argv[3] if len(sys.argv) > 3 else "phantom:abdomen?size=96"
vpm = os.path.join(build, "client", "vpm")
server_bin = os.path.join(build, "server", "service", "vpm-server")
work = tempfile.mkdtemp(prefix="vpm-soak-")
users = [f"user{i:02d}" for i in range(16)]
tokens = {u: os.urandom(16).hex() for u in users}
lines = []
for u in users:
    out = subprocess.run([server_bin, "--hash-token", u], input=tokens[u], capture_output=True,
                         text=True, check=True).stdout.strip()
    lines.append(out)
with open(os.path.join(work, "users"), "w") as f:
    f.write("\n".join(lines) + "\n")
log = open(os.path.join(work, "server.log"), "w")
server = subprocess.Popen([server_bin, "--listen", "127.0.0.1:0", "--users", os.path.join(work, "users"),
                           "--max-sessions", "64", "--max-sessions-per-user", "4",
                           "--metrics-listen", "127.0.0.1:0"],
                          stdout=log, stderr=subprocess.STDOUT)
port = metrics_port = None
for _ in range(400):
    text = open(os.path.join(work, "server.log")).read()
    if "listening on port" in text:
        port = text.split("listening on port")[1].split()[0]
        if "metrics on port" in text:
            metrics_port = text.split("metrics on port")[1].split()[0].rstrip(",;)")
        break
    time.sleep(0.05)
if port is None:
    sys.exit("vpm-server did not start: " + open(os.path.join(work, "server.log")).read())
addr = f"127.0.0.1:{port}"

def proc_stats():
    status = open(f"/proc/{server.pid}/status").read()
    rss = int([l for l in status.splitlines() if l.startswith("VmRSS:")][0].split()[1])
    threads = int([l for l in status.splitlines() if l.startswith("Threads:")][0].split()[1])
    fds = len(os.listdir(f"/proc/{server.pid}/fd"))
    stats = {"rss_mib": rss / 1024, "threads": threads, "fds": fds}
    stats.update(server_metrics())
    return stats

def server_metrics():
    """Streams opened and closed, open streams, sessions (the server's /metrics)."""
    wanted = {"vpm_streams_opened_total": "opened", "vpm_streams_closed_total": "closed",
              "vpm_open_streams": "open", "vpm_sessions": "sessions"}
    if metrics_port is None:
        return {}
    try:
        import urllib.request
        text = urllib.request.urlopen(f"http://127.0.0.1:{metrics_port}/metrics", timeout=5).read()
    except OSError:
        return {}
    out = {}
    for line in text.decode().splitlines():
        name = line.split("{")[0].split(" ")[0]
        if name in wanted:
            out[wanted[name]] = out.get(wanted[name], 0) + float(line.split()[-1])
        elif name == "vpm_unary_calls_in_flight" and float(line.split()[-1]) != 0:
            method = line.split('method="')[1].split('"')[0]
            out.setdefault("unary_in_flight", {})[method] = float(line.split()[-1])
    return out

script = os.path.join(work, "drag.json")
with open(script, "w") as f:
    json.dump({"volume": source, "settings": {"width": 256, "height": 256}, "interval_ms": 33,
               "steps": [{"camera": {"azimuth_deg": 0, "elevation_deg": 10}},
                         {"grab": {"landmark": "left_renal_artery"}},
                         {"drag": {"to_mm": [0, 0, 12], "steps": 40}},
                         {"release": {}}]}, f)
upload_file = os.path.join(work, "upload.nii")
subprocess.run([vpm, "volume", "export", "phantom:abdomen?size=48", upload_file],
               check=True, capture_output=True)

lock = threading.Lock()
errors, expected, done, reports = [], {}, {}, {u: [] for u in users}

def run(user, args, timeout=120, expect=()):
    env = dict(os.environ, VPM_TOKEN=tokens[user])
    p = subprocess.run([vpm, "--server", addr] + args, env=env, capture_output=True, text=True,
                       timeout=timeout)
    if p.returncode == 0:
        words = args[2:] if args[0].startswith("--") else args  # past --deadline-s S
        what = words[0] if words[0] in ("play", "snapshot") else " ".join(words[:2])
        with lock:
            done[what] = done.get(what, 0) + 1
    else:
        lines = (p.stderr or p.stdout).strip().splitlines()
        text = lines[-1] if lines else f"exit {p.returncode}"
        # A play that lost its session says why first ("session S lost (CODE: why)").
        lost = [l for l in lines if " lost (" in l]
        if lost and lost[0] != text:
            text += f" [{lost[0]}]"
        with lock:
            code = next((e for e in expect if e in text), None)
            if code:
                expected[code] = expected.get(code, 0) + 1
            else:
                errors.append(f"{user} {' '.join(args[:2])}: {text}")
    return p

def play(user, interrupt=False):
    report = os.path.join(work, f"{user}-{time.monotonic_ns()}.json")
    if not interrupt:
        run(user, ["play", script, "--report", report])
        if os.path.exists(report):
            with lock:
                reports[user].append(json.load(open(report)))
        return
    env = dict(os.environ, VPM_TOKEN=tokens[user])
    p = subprocess.Popen([vpm, "--server", addr, "play", script], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(random.uniform(0.3, 1.5))
    p.send_signal(signal.SIGINT)
    p.wait()
    with lock:
        expected["interrupted play"] = expected.get("interrupted play", 0) + 1

def field(p, key):
    """`key` of the JSON object a `vpm` command printed, or None."""
    try:
        return json.loads(p.stdout).get(key)
    except (ValueError, AttributeError):
        return None

def planner(user, end, counter):
    n = 0
    while time.monotonic() < end:
        n += 1
        play(user, interrupt=(n % 4 == 0 and counter is not None))

def uploader(user, end):
    while time.monotonic() < end:
        p = run(user, ["volume", "upload", upload_file])
        vid = field(p, "volume_id")
        if vid:
            run(user, ["volume", "delete", vid])

def open_session(user):
    p = run(user, ["volume", "load", source])
    vid = field(p, "volume_id")
    return run(user, ["session", "open", "--volume-id", vid]) if vid else p

def watcher(user, end):
    while time.monotonic() < end:
        p = open_session(user)
        sid = field(p, "session_id")
        if not sid:
            time.sleep(1)
            continue
        env = dict(os.environ, VPM_TOKEN=tokens[user])
        w = subprocess.Popen([vpm, "--server", addr, "watch", "--session", sid, "--frames", "100000"],
                             env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(random.uniform(1, 3))
        w.send_signal(signal.SIGKILL)
        w.wait()
        with lock:
            expected["killed watch"] = expected.get("killed watch", 0) + 1
        run(user, ["session", "close", sid])

def hammer(user, end):
    p = open_session(user)
    sid = field(p, "session_id")
    n = 0
    while sid and time.monotonic() < end:
        n += 1
        short = n % 3 == 0
        run(user, (["--deadline-s", "0.005"] if short else []) +
            ["snapshot", "--session", sid, "--size", "256", "256", "--out",
             os.path.join(work, "hammer.jpg")],
            expect=("DEADLINE_EXCEEDED", "RESOURCE_EXHAUSTED") if short else ("RESOURCE_EXHAUSTED",))
    if sid:
        run(user, ["session", "close", sid])

def fps_of(user_list, seconds):
    frames = sum(r["frames"] for u in user_list for r in reports[u])
    return frames / seconds

# Baseline: 2 planners alone.
base_s = 20
end = time.monotonic() + base_s
threads = [threading.Thread(target=planner, args=(u, end, None)) for u in users[:2]]
[t.start() for t in threads]
[t.join() for t in threads]
base_fps = fps_of(users[:2], base_s)
base_lat = [r["latency_ms"] for u in users[:2] for r in reports[u]]
for u in users:
    reports[u] = []
time.sleep(2)

stats = {"before": proc_stats()}
churn_s = minutes * 60
end = time.monotonic() + churn_s
threads = [threading.Thread(target=planner, args=(u, end, 0)) for u in users[:12]]
threads += [threading.Thread(target=uploader, args=(users[12], end)),
            threading.Thread(target=watcher, args=(users[13], end)),
            threading.Thread(target=hammer, args=(users[14], end)),
            threading.Thread(target=planner, args=(users[15], end, 0))]
[t.start() for t in threads]
# Under load: "start" once the churn is warm (a tenth in: every user's
# volumes, meshes and pools exist), "middle", "end" (just before the loops
# stop); then "idle" once every client is gone.
time.sleep(churn_s / 10)
stats["start"] = proc_stats()
time.sleep(churn_s * 4 / 10)
stats["middle"] = proc_stats()
time.sleep(max(0.0, end - time.monotonic() - 2))
stats["end"] = proc_stats()
[t.join() for t in threads]
time.sleep(3)
stats["idle"] = proc_stats()
idle = stats["idle"]
if "opened" in idle and idle["opened"] != idle["closed"]:
    errors.append(f"idle, every client gone: {idle['opened'] - idle['closed']:.0f} streams "
                  "opened were never closed (a reactor that never finished)")
if idle.get("unary_in_flight"):
    errors.append(f"idle, every client gone: unary calls never answered: {idle['unary_in_flight']}")
if idle.get("sessions", 0) > 0:
    errors.append(f"idle, every client gone: {idle['sessions']:.0f} sessions left open")
server.send_signal(signal.SIGTERM)
try:
    code = server.wait(timeout=30)
except subprocess.TimeoutExpired:
    # Still running 30 s after SIGTERM (its grace is 5 s): an error, reported
    # with the figures, and the server killed.
    errors.append("vpm-server did not exit within 30 s of SIGTERM (killed)")
    server.kill()
    code = server.wait()

planners = users[:12] + [users[15]]
print(f"churn soak: 16 users, {minutes:g} min, {source}")
print(f"unexpected errors: {len(errors)}")
for e in errors[:20]:
    print("  ", e)
print("completed calls:", ", ".join(f"{k} {v}" for k, v in sorted(done.items())))
print("expected outcomes:", ", ".join(f"{k} {v}" for k, v in sorted(expected.items())) or "none")
print(f"aggregate fps of the planners: {fps_of(planners, churn_s):.1f} "
      f"(2 planners alone: {base_fps:.1f})")
print(f"{'user':>8} {'plays':>6} {'fps':>6} {'p50 ms':>8} {'p99 ms':>8}")
for u in planners:
    rs = reports[u]
    if not rs:
        print(f"{u:>8} {0:>6}")
        continue
    fps = sum(r["frames"] for r in rs) / churn_s
    p50 = sorted(r["latency_ms"].get("p50", 0) for r in rs)[len(rs) // 2]
    p99 = max(r["latency_ms"].get("p99", 0) for r in rs)
    print(f"{u:>8} {len(rs):>6} {fps:>6.1f} {p50:>8.1f} {p99:>8.1f}")
print(f"{'':>8} {'RSS MiB':>8} {'threads':>8} {'fds':>6} {'streams opened/closed/open':>27} "
      f"{'sessions':>8}")
for k in ("before", "start", "middle", "end", "idle"):
    s = stats[k]
    streams = (f"{s.get('opened', -1):.0f}/{s.get('closed', -1):.0f}/{s.get('open', -1):.0f}"
               if "opened" in s else "-")
    print(f"{k:>8} {s['rss_mib']:>8.1f} {s['threads']:>8} {s['fds']:>6} {streams:>27} "
          f"{s.get('sessions', -1):>8.0f}")
growth = stats["end"]["rss_mib"] / stats["start"]["rss_mib"] - 1
print(f"RSS end vs start, both under load: {100 * growth:+.1f}% (goal within 10%); "
      f"server exit code {code}")
sys.exit(1 if errors else 0)
