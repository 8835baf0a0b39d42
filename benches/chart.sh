#!/usr/bin/env bash
# Side by side (issue #15): the size-chart flow (ASTM chart, 12 sizes) and the
# scan flow through `grade3d grade`, for this working tree and for a base
# commit built from a git worktree, in one run; wall time min/median/max over
# RUNS runs each, the ratio this/base of the medians, and per stage (the
# `timings_ms` the service reports, printed by `grade --timings`) the median
# of each side and their ratio. For a scan, "request" is the sum of its
# stages: one request's work in the running service, without the process's
# start and GPU context (a single body's stages run one after another), and
# without the "block" stage: a template's block (its dart plan on its
# reference body, grade3d-service's `blocks`) is made once per process,
# and the service makes the live templates' blocks as it starts.
#
# Then the same 12-size charts as requests to a running `serve` (its start,
# renderer, body model and template blocks behind it, as in production; the
# result cache off and every request's chart distinct), wall per request.
#
# Then the 2D peer: FreeSewing (benches/peer/freesewing: @freesewing/core
# with the titan trouser block and the bella bodice block) drafting and
# rendering the same 12 sizes to SVG, timed in one Node process over RUNS
# runs; our 12-size grade's median over theirs (warm, in process, and their
# cold process including Node's start). Skipped when npm is missing.
#
#   benches/chart.sh [BASE_REV (default: origin/main, else HEAD)] [RUNS (default 5)]
#
# Run it on an otherwise idle machine. Both binaries are built with the
# release profile into target/bench/ (the base from target/bench/worktree).
set -euo pipefail
cd "$(dirname "$0")/.."
base_rev=${1:-$(git rev-parse --verify -q origin/main || git rev-parse HEAD)}
runs=${2:-5}
out=target/bench
mkdir -p "$out"

# the base commit's binary, built in its own worktree and target directory
git worktree remove --force "$out/worktree" >/dev/null 2>&1 || true
git worktree add --force --detach "$out/worktree" "$base_rev" >/dev/null
(cd "$out/worktree" && CARGO_TARGET_DIR="$PWD/../target" cargo build --release --bin grade3d -q)
cp "$out/target/release/grade3d" "$out/grade3d-base"
git worktree remove --force "$out/worktree"
cargo build --release --bin grade3d -q
cp target/release/grade3d "$out/grade3d-this"

# the peer's packages, from its lock file
peer=benches/peer/freesewing
if command -v npm >/dev/null && [ ! -d "$peer/node_modules" ]; then
    (cd "$peer" && npm ci --silent --no-audit --no-fund)
fi

python3 - "$out" "$runs" "$(git rev-parse --short "$base_rev")" "$peer" <<'PY'
import json, os, shutil, statistics, subprocess, sys, time
out, runs, base, peer = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
chart = "fixtures/size-charts/astm-d5585-11-misses-partial.csv"
body = "fixtures/bodies/female-average-caucasian"
scan = ["--scan", body + ".glb", "--landmarks", body + ".landmarks.json"]
cases = [
    ("chart 12 sizes: trousers", ["--chart", chart, "--base-size", "8", "--templates", "trousers"]),
    ("chart 12 sizes: fitted-bodice", ["--chart", chart, "--base-size", "8", "--templates", "fitted-bodice"]),
    ("chart 12 sizes: all three", ["--chart", chart, "--base-size", "8", "--templates", "straight-skirt,trousers,fitted-bodice"]),
    ("scan: straight-skirt", scan + ["--templates", "straight-skirt"]),
    ("scan: trousers", scan + ["--templates", "trousers"]),
    ("scan: fitted-bodice", scan + ["--templates", "fitted-bodice"]),
]
binaries = ["grade3d-base", "grade3d-this"]
# an older base may not print its stage timings
has_timings = {
    b: "--timings" in subprocess.run([f"{out}/{b}", "grade", "--help"], capture_output=True, text=True).stdout
    for b in binaries
}

def run(binary, args):
    """Wall time (s) and stage timings (ms) of one `grade` process."""
    dest = f"{out}/artefacts"
    shutil.rmtree(dest, ignore_errors=True)
    extra = ["--timings"] if has_timings[binary] else []
    t = time.perf_counter()
    p = subprocess.run([f"{out}/{binary}", "grade", *args, "--out", dest, "--created", "2026-01-01T00:00:00Z", *extra],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t
    stages = {}
    for line in p.stderr.splitlines():
        if line.startswith("timings_ms "):
            stages = json.loads(line[len("timings_ms "):])
    return wall, stages

fmt = lambda v: f"{min(v):.2f}/{statistics.median(v):.2f}/{max(v):.2f}"
med = statistics.median
ours = {}
print(f"{'case':32} {'base ' + base + ' (s) min/med/max':>28} {'this (s) min/med/max':>24} {'this/base':>9}")
for name, args in cases:
    walls = {b: [] for b in binaries}
    stages = {b: [] for b in binaries}
    for _ in range(runs):  # interleaved, so that a drift in the machine hits both alike
        for b in binaries:
            w, s = run(b, args)
            walls[b].append(w)
            stages[b].append(s)
    wb, wh = walls["grade3d-base"], walls["grade3d-this"]
    ours[name] = med(wh)
    print(f"{name:32} {fmt(wb):>28} {fmt(wh):>24} {med(wh) / med(wb):>9.2f}")
    names = sorted({k for s in stages["grade3d-this"] for k in s})
    if name.startswith("scan"):
        for s in stages.values():
            for d in s:
                if d:
                    # the block is made once per process and template (the service makes them as it
                    # starts): not a request's work
                    d["request"] = sum(v for k, v in d.items() if k != "block")
        names.append("request")
    for stage in names:
        vb = [s[stage] for s in stages["grade3d-base"] if stage in s]
        vh = [s[stage] for s in stages["grade3d-this"] if stage in s]
        mb = f"{med(vb):.0f} ms" if vb else "-"
        ratio = f"{med(vh) / med(vb):.2f}" if vb and med(vb) > 0 else "-"
        print(f"  {stage:30} {mb:>28} {med(vh):>21.0f} ms {ratio:>9}")

# the same 12-size runs as requests to a running service (`serve`, its start, renderer, body model and
# blocks behind it, as in production): POST /v1/grade/size-chart with the result cache off, each request's
# chart distinct (the base size's neck girth moved by a distinct thousandth of an inch, so every size's body,
# fitted or graded from it, and its obstacle are new); wall time of each request as the client sees it
import socket, urllib.request

def free_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]

def service_walls(binary, templates):
    port = free_port()
    data = f"{out}/serve-data-{binary}"
    shutil.rmtree(data, ignore_errors=True)
    server = subprocess.Popen([f"{out}/{binary}", "serve", "--addr", f"127.0.0.1:{port}", "--data-dir", data,
                               "--result-cache-bytes", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}"
    try:
        for _ in range(600):
            try:
                if urllib.request.urlopen(f"{url}/readyz", timeout=1).status == 200:
                    break
            except Exception:
                time.sleep(0.1)
        lines = open(chart).read().splitlines()
        def request(k):
            body = []
            for line in lines:
                cells = line.split(",")
                if cells[0] == "8":
                    cells[2] = f"{float(cells[2]) + 0.001 * k:.3f}"
                body.append(",".join(cells))
            req = urllib.request.Request(f"{url}/v1/grade/size-chart?templates={templates}&base_size=8",
                                         data="\n".join(body).encode(), headers={"Content-Type": "text/csv"})
            t = time.perf_counter()
            with urllib.request.urlopen(req, timeout=120) as r:
                r.read()
            return time.perf_counter() - t
        request(0)  # the first request after start (warms the pool; the blocks are made at start)
        return [request(k + 1) for k in range(runs)]
    finally:
        server.terminate()
        server.wait()

print(f"\nThe same charts as requests to a running service (result cache off, a distinct chart each request), {runs} runs")
print(f"{'case':32} {'base ' + base + ' (s) min/med/max':>28} {'this (s) min/med/max':>24} {'this/base':>9}")
for name, templates in (("service 12 sizes: trousers", "trousers"), ("service 12 sizes: fitted-bodice", "fitted-bodice"),
                        ("service 12 sizes: all three", "straight-skirt,trousers,fitted-bodice")):
    wb, wh = service_walls("grade3d-base", templates), service_walls("grade3d-this", templates)
    print(f"{name:32} {fmt(wb):>28} {fmt(wh):>24} {med(wh) / med(wb):>9.2f}")

# the 2D peer
if not os.path.isdir(f"{peer}/node_modules"):
    print("\nFreeSewing peer skipped (no npm, or benches/peer/freesewing has no node_modules)")
    sys.exit(0)
print(f"\nFreeSewing (benches/peer/freesewing), 12 sizes drafted and rendered to SVG, {runs} runs in one process")
p = subprocess.run(["node", "draft.mjs", "--runs", str(runs), "--design", "both"], cwd=peer,
                   check=True, capture_output=True, text=True)
theirs = {}
for line in p.stdout.splitlines():
    line = line.strip()
    if line.startswith("{"):
        r = json.loads(line)
        theirs[r["design"]] = r
cold = {}
for design in ("titan", "bella"):
    walls = []
    for _ in range(runs):
        t = time.perf_counter()
        subprocess.run(["node", "draft.mjs", "--runs", "1", "--design", design], cwd=peer, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t)
    cold[design] = walls
print(f"{'design':10} {'first (ms)':>10} {'warm min/med/max (ms)':>24} {'cold process (s)':>20} {'ours/theirs warm':>17} {'ours/theirs cold':>17}")
for design, case in (("titan", "chart 12 sizes: trousers"), ("bella", "chart 12 sizes: fitted-bodice")):
    r = theirs.get(design)
    if not r:
        continue
    warm = f"{r['min_ms']:.1f}/{r['median_ms']:.1f}/{r['max_ms']:.1f}"
    print(f"{design:10} {r['first_ms']:>10.1f} {warm:>24} {fmt(cold[design]):>20} "
          f"{ours[case] * 1e3 / r['median_ms']:>17.1f} {ours[case] / med(cold[design]):>17.1f}")
PY
