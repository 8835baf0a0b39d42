#!/usr/bin/env bash
# Side by side (issue #15): the size-chart flow (ASTM chart, 12 sizes) and the
# scan flow through `grade3d grade`, for this working tree and for a base
# commit built from a git worktree, in one run; wall time min/median/max over
# RUNS runs each, and the ratio this/base of the medians.
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

python3 - "$out" "$runs" "$(git rev-parse --short "$base_rev")" <<'PY'
import statistics, subprocess, sys, time, shutil
out, runs, base = sys.argv[1], int(sys.argv[2]), sys.argv[3]
chart = "fixtures/size-charts/astm-d5585-11-misses-partial.csv"
body = "fixtures/bodies/female-average-caucasian"
cases = [
    ("chart 12 sizes: trousers", ["--chart", chart, "--base-size", "8", "--templates", "trousers"]),
    ("chart 12 sizes: fitted-bodice", ["--chart", chart, "--base-size", "8", "--templates", "fitted-bodice"]),
    ("chart 12 sizes: all three", ["--chart", chart, "--base-size", "8", "--templates", "straight-skirt,trousers,fitted-bodice"]),
    ("scan: straight-skirt", ["--scan", body + ".glb", "--landmarks", body + ".landmarks.json", "--templates", "straight-skirt"]),
    ("scan: trousers", ["--scan", body + ".glb", "--landmarks", body + ".landmarks.json", "--templates", "trousers"]),
    ("scan: fitted-bodice", ["--scan", body + ".glb", "--landmarks", body + ".landmarks.json", "--templates", "fitted-bodice"]),
]
def run(binary, args):
    dest = f"{out}/artefacts"
    shutil.rmtree(dest, ignore_errors=True)
    t = time.perf_counter()
    subprocess.run([f"{out}/{binary}", "grade", *args, "--out", dest, "--created", "2026-01-01T00:00:00Z"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - t
print(f"{'case':32} {'base ' + base + ' (s) min/med/max':>28} {'this (s) min/med/max':>24} {'this/base':>9}")
for name, args in cases:
    times = {"grade3d-base": [], "grade3d-this": []}
    for _ in range(runs):  # interleaved, so that a drift in the machine hits both alike
        for binary in times:
            times[binary].append(run(binary, args))
    b, h = times["grade3d-base"], times["grade3d-this"]
    fmt = lambda v: f"{min(v):.2f}/{statistics.median(v):.2f}/{max(v):.2f}"
    print(f"{name:32} {fmt(b):>28} {fmt(h):>24} {statistics.median(h) / statistics.median(b):>9.2f}")
PY
