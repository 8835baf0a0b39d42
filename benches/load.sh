#!/usr/bin/env bash
# Load test of the HTTP service (wrk).
#
#   benches/load.sh [BINARY]        (default: target/release/grade3d)
#
# Starts `BINARY serve` on a free port with a temporary data dir, waits for
# GET /readyz, then drives four flows at concurrency 1, 16 and 64:
#
#   size-chart-cached    POST /v1/grade/size-chart, text/csv, the ASTM fixture
#                        (identical body: served from the result cache)
#   size-chart-uncached  POST /v1/grade/size-chart, application/json, a one-size
#                        chart whose bust girth differs on every request
#   scan-cached          POST /v1/grade/scan, multipart (scan GLB, landmarks,
#                        template=straight-skirt), identical body
#   scan-uncached        the same, with one landmark coordinate (ankle_left x)
#                        moved by a distinct sub-millimetre amount per request
#
# Cached flows are primed with one request (not measured) first. Between runs
# the script waits for the server's work queue to drain.
#
# For every run it reports requests/s, p50/p99 latency, the count of 2xx, of
# 503 and of any other status, socket errors (connect/read/write/timeout), the
# server's result-cache hits during the run (must be 0 for uncached flows), the
# server's peak RSS during the run (VmHWM, reset before each run through
# /proc/PID/clear_refs where allowed, and polled VmRSS) and its RSS after the run.
# The table goes to stdout and to target/load-report.md.
#
# Exits non-zero when any response is neither 2xx nor 503, on any socket
# error, when the server dies, when peak RSS exceeds MAX_RSS_MB, or when an
# uncached run whose concurrency exceeds the pool's capacity (workers +
# queue depth) saw no 503 at all (the queue would not be bounded), or when an
# uncached run hit the result cache (its requests were not all distinct).
#
# Environment:
#   DURATION     seconds per run (default 30; "30s" accepted)
#   CONCURRENCY  space-separated list (default "1 16 64")
#   FLOWS        space-separated subset of the four flows above (default all)
#   MAX_RSS_MB   bound on the server's peak RSS (default 4096)
#   WRK_THREADS  most wrk threads (default 2)
#   SERVER_ARGS  extra arguments to `serve` (e.g. "--no-gpu")
#   GRADE3D_WORKERS / GRADE3D_QUEUE_DEPTH are read by the server too; the
#   script uses them (defaults: nproc / 16) for the capacity check.
#
# Needs wrk (installed with apt-get when missing), curl and python3 (free port).
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
BIN=${1:-$ROOT/target/release/grade3d}
[[ $BIN == /* ]] || BIN=$(pwd)/$BIN
DURATION=${DURATION:-30}
DURATION=${DURATION%s}
CONCURRENCY=${CONCURRENCY:-"1 16 64"}
FLOWS=${FLOWS:-"size-chart-cached size-chart-uncached scan-cached scan-uncached"}
MAX_RSS_MB=${MAX_RSS_MB:-4096}
WRK_THREADS=${WRK_THREADS:-2}
WORKERS=${GRADE3D_WORKERS:-$(nproc)}
QUEUE_DEPTH=${GRADE3D_QUEUE_DEPTH:-16}
CAPACITY=$((WORKERS + QUEUE_DEPTH))
REPORT=$ROOT/target/load-report.md

CSV=$ROOT/fixtures/size-charts/astm-d5585-11-misses-partial.csv
GLB=$ROOT/fixtures/bodies/female-average-caucasian.glb
LANDMARKS=$ROOT/fixtures/bodies/female-average-caucasian.landmarks.json
SIZE_CHART_CSV_PATH='/v1/grade/size-chart?templates=straight-skirt&base_size=8'

die() { echo "load.sh: $*" >&2; exit 2; }

[[ -x $BIN ]] || die "no executable server binary at $BIN (build with cargo build --release, or pass a path)"
[[ $DURATION =~ ^[0-9]+$ && $DURATION -gt 0 ]] || die "DURATION must be a whole number of seconds"
for f in "$CSV" "$GLB" "$LANDMARKS"; do [[ -r $f ]] || die "missing fixture $f"; done
for t in curl python3; do command -v "$t" >/dev/null || die "$t is required"; done

# --- the load generator ---------------------------------------------------------------------
if ! command -v wrk >/dev/null; then
    echo "wrk not found: installing it with apt-get" >&2
    SUDO=""
    [[ $(id -u) -eq 0 ]] || SUDO=sudo
    $SUDO apt-get install -y wrk >/dev/null 2>&1 || { $SUDO apt-get update >/dev/null && $SUDO apt-get install -y wrk >/dev/null; } \
        || die "could not install wrk"
fi

WORK=$(mktemp -d "${TMPDIR:-/tmp}/grade3d-load.XXXXXX")
SERVER_PID=""
POLL_PID=""
cleanup() {
    [[ -n $POLL_PID ]] && kill "$POLL_PID" 2>/dev/null || true
    if [[ -n $SERVER_PID ]]; then
        kill "$SERVER_PID" 2>/dev/null || true
        wait "$SERVER_PID" 2>/dev/null || true
    fi
    rm -rf "$WORK"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# --- the wrk script -------------------------------------------------------------------------
# args (after the URL): mode seed nthreads csv glb landmarks csv-path
cat >"$WORK/load.lua" <<'LUA'
local threads = {}
local next_tid = 0

function setup(thread)
    thread:set("tid", next_tid)
    next_tid = next_tid + 1
    table.insert(threads, thread)
end

local function slurp(path)
    local f = assert(io.open(path, "rb"))
    local s = f:read("*a")
    f:close()
    return s
end

local BOUNDARY = "grade3dLoadBoundary7MA4YWxkTrZu0gW"

function init(args)
    -- args[0] is the URL
    mode = args[1]
    seed = tonumber(args[2])
    nthreads = tonumber(args[3])
    n = 0
    codes = {}
    wrk.method = "POST"
    if mode == "size-chart-cached" then
        wrk.path = args[7]
        wrk.headers["Content-Type"] = "text/csv"
        wrk.body = slurp(args[4])
        fixed = wrk.format()
    elseif mode == "size-chart-uncached" then
        wrk.path = "/v1/grade/size-chart"
        wrk.headers["Content-Type"] = "application/json"
    elseif mode == "scan-cached" or mode == "scan-uncached" then
        wrk.path = "/v1/grade/scan"
        wrk.headers["Content-Type"] = "multipart/form-data; boundary=" .. BOUNDARY
        local glb, lm = slurp(args[5]), slurp(args[6])
        local head = "--" .. BOUNDARY .. "\r\n"
            .. "Content-Disposition: form-data; name=\"template\"\r\n\r\n"
            .. "straight-skirt\r\n"
            .. "--" .. BOUNDARY .. "\r\n"
            .. "Content-Disposition: form-data; name=\"landmarks\"; filename=\"landmarks.json\"\r\n"
            .. "Content-Type: application/json\r\n\r\n"
        local tail = "\r\n--" .. BOUNDARY .. "\r\n"
            .. "Content-Disposition: form-data; name=\"scan\"; filename=\"scan.glb\"\r\n"
            .. "Content-Type: model/gltf-binary\r\n\r\n"
            .. glb .. "\r\n--" .. BOUNDARY .. "--\r\n"
        if mode == "scan-cached" then
            wrk.body = head .. lm .. tail
            fixed = wrk.format()
        else
            -- split the landmarks around ankle_left's x coordinate
            local s, e = string.find(lm, '"ankle_left"%s*:%s*%[%s*')
            assert(s, "no ankle_left in the landmarks")
            local ns, ne = string.find(lm, "[%-%d%.eE+]+", e + 1)
            ankle_x = tonumber(string.sub(lm, ns, ne))
            prefix = head .. string.sub(lm, 1, ns - 1)
            suffix = string.sub(lm, ne + 1) .. tail
        end
    else
        error("unknown mode " .. tostring(mode))
    end
end

-- a number distinct per request across threads and runs (seed: 1e7 per run)
local function key()
    n = n + 1
    return seed + tid + nthreads * n
end

function request()
    if fixed then
        return fixed
    elseif mode == "size-chart-uncached" then
        local bust = 80 + key() * 1e-7
        local body = string.format('{"templates":["straight-skirt"],"chart":{"unit":"cm","sizes":[{"size":"S",'
            .. '"measurements":{"bust_girth":%.7f,"waist_girth":68,"hip_girth":94}}]}}', bust)
        return wrk.format(nil, nil, nil, body)
    else
        local x = string.format("%.13f", ankle_x + key() * 1e-11)
        return wrk.format(nil, nil, nil, prefix .. x .. suffix)
    end
end

function response(status, headers, body)
    codes[status] = (codes[status] or 0) + 1
end

function done(summary, latency, requests)
    local all = {}
    for _, t in ipairs(threads) do
        local c = t:get("codes")
        if c then
            for k, v in pairs(c) do all[k] = (all[k] or 0) + v end
        end
    end
    local ok, busy, other, list = 0, 0, 0, {}
    for k, v in pairs(all) do
        if k >= 200 and k < 300 then ok = ok + v
        elseif k == 503 then busy = busy + v
        else other = other + v end
        table.insert(list, k .. ":" .. v)
    end
    table.sort(list)
    local e = summary.errors
    io.write(string.format(
        "RESULT requests=%d duration_us=%d p50_us=%d p99_us=%d max_us=%d ok=%d busy=%d other=%d "
            .. "connect=%d read=%d write=%d timeout=%d codes=%s\n",
        summary.requests, summary.duration, latency:percentile(50), latency:percentile(99), latency.max,
        ok, busy, other, e.connect, e.read, e.write, e.timeout, table.concat(list, ",")))
end
LUA

# --- the server -----------------------------------------------------------------------------
PORT=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
BASE=http://127.0.0.1:$PORT
mkdir -p "$WORK/data"
# shellcheck disable=SC2086
"$BIN" serve --addr "127.0.0.1:$PORT" --data-dir "$WORK/data" ${SERVER_ARGS:-} >"$WORK/server.log" 2>&1 &
SERVER_PID=$!

alive() { kill -0 "$SERVER_PID" 2>/dev/null; }
server_died() {
    echo "load.sh: the server (pid $SERVER_PID) died; its log:" >&2
    tail -n 40 "$WORK/server.log" >&2
    exit 1
}

for _ in $(seq 600); do
    alive || server_died
    [[ $(curl -s -o /dev/null -w '%{http_code}' "$BASE/readyz") == 200 ]] && break
    sleep 0.2
done
[[ $(curl -s -o /dev/null -w '%{http_code}' "$BASE/readyz") == 200 ]] || die "the server was not ready after 120 s"
READY=$(curl -s "$BASE/readyz")
echo "server pid $SERVER_PID on $BASE: $READY" >&2

kb() { awk -v k="$1:" '$1 == k { print $2 }' "/proc/$SERVER_PID/status" 2>/dev/null || echo 0; }
queue_depth() { curl -s "$BASE/metrics" | awk '$1 == "grade3d_queue_depth" { print $2 }'; }
cache_hits() {
    curl -s "$BASE/metrics" | awk '/^grade3d_cache_lookups_total\{/ && /cache="results"/ && /outcome="hit"/ { n = $2 } END { print n + 0 }'
}
drain() {
    for _ in $(seq 300); do
        [[ $(queue_depth) == 0 ]] && return 0
        sleep 0.2
    done
    echo "load.sh: warning: the work queue did not drain within 60 s" >&2
}

prime() {
    local code
    case $1 in
        size-chart-cached)
            code=$(curl -s -o /dev/null -w '%{http_code}' -H 'Content-Type: text/csv' --data-binary "@$CSV" \
                "$BASE$SIZE_CHART_CSV_PATH") ;;
        scan-cached)
            code=$(curl -s -o /dev/null -w '%{http_code}' -F "template=straight-skirt" \
                -F "landmarks=@$LANDMARKS;type=application/json" -F "scan=@$GLB;type=model/gltf-binary" "$BASE/v1/grade/scan") ;;
        *) return 0 ;;
    esac
    [[ $code == 200 ]] || die "priming $1 answered $code"
}

ms() { awk -v u="$1" 'BEGIN { if (u >= 1e6) printf "%.2f s", u / 1e6; else printf "%.1f ms", u / 1e3 }'; }

# --- the runs ---------------------------------------------------------------------------------
FAIL=()
ROWS=()
RUN=0
echo "duration ${DURATION}s per run; pool capacity $CAPACITY (workers $WORKERS + queue $QUEUE_DEPTH)" >&2
for flow in $FLOWS; do
    case $flow in
        size-chart-cached | size-chart-uncached | scan-cached | scan-uncached) ;;
        *) die "unknown flow $flow" ;;
    esac
    prime "$flow"
    for c in $CONCURRENCY; do
        RUN=$((RUN + 1))
        alive || server_died
        drain
        threads=$((c < WRK_THREADS ? c : WRK_THREADS))
        # reset the high-water mark (owner or root only); the poller is the fallback
        echo 5 >"/proc/$SERVER_PID/clear_refs" 2>/dev/null || true
        hits0=$(cache_hits)
        (
            peak=0
            while kill -0 "$SERVER_PID" 2>/dev/null; do
                r=$(kb VmRSS)
                r=${r:-0}
                ((r > peak)) && peak=$r && echo "$peak" >"$WORK/poll.kb"
                sleep 0.25
            done
        ) &
        POLL_PID=$!
        echo "== $flow, concurrency $c, ${DURATION}s" >&2
        log=$WORK/wrk-$flow-$c.log
        nice -n 10 wrk -t "$threads" -c "$c" -d "${DURATION}s" --timeout 130s --latency -s "$WORK/load.lua" \
            -- "$BASE/" "$flow" $((RUN * 10000000)) "$threads" "$CSV" "$GLB" "$LANDMARKS" "$SIZE_CHART_CSV_PATH" \
            >"$log" 2>&1 || true
        kill "$POLL_PID" 2>/dev/null || true
        wait "$POLL_PID" 2>/dev/null || true
        POLL_PID=""
        alive || server_died
        hits=$(($(cache_hits) - hits0))
        hwm=$(kb VmHWM)
        polled=$(cat "$WORK/poll.kb" 2>/dev/null || echo 0)
        rm -f "$WORK/poll.kb"
        rss=$(kb VmRSS)
        peak_kb=$((hwm > polled ? hwm : polled))
        line=$(grep '^RESULT ' "$log" || true)
        if [[ -z $line ]]; then
            cat "$log" >&2
            die "wrk gave no result for $flow at $c"
        fi
        declare -A R=()
        for kv in ${line#RESULT }; do R[${kv%%=*}]=${kv#*=}; done
        rps=$(awk -v n="${R[requests]}" -v d="${R[duration_us]}" 'BEGIN { printf "%.1f", (d > 0 ? n / (d / 1e6) : 0) }')
        okps=$(awk -v n="${R[ok]}" -v d="${R[duration_us]}" 'BEGIN { printf "%.1f", (d > 0 ? n / (d / 1e6) : 0) }')
        sock=$((R[connect] + R[read] + R[write] + R[timeout]))
        peak_mb=$((peak_kb / 1024))
        rss_mb=$((rss / 1024))
        ROWS+=("| $flow | $c | $rps | $okps | $(ms "${R[p50_us]}") | $(ms "${R[p99_us]}") | ${R[ok]} | ${R[busy]} | ${R[other]} | $sock | $hits | $peak_mb | $rss_mb |")
        echo "   ${R[requests]} requests, $rps/s, p50 $(ms "${R[p50_us]}"), p99 $(ms "${R[p99_us]}"), statuses ${R[codes]:-none}, socket errors $sock, result-cache hits $hits, peak RSS $peak_mb MB" >&2
        ((R[other] == 0)) || FAIL+=("$flow c=$c: ${R[other]} responses neither 2xx nor 503 (${R[codes]})")
        ((sock == 0)) || FAIL+=("$flow c=$c: socket errors connect=${R[connect]} read=${R[read]} write=${R[write]} timeout=${R[timeout]}")
        ((peak_mb <= MAX_RSS_MB)) || FAIL+=("$flow c=$c: peak RSS $peak_mb MB > MAX_RSS_MB=$MAX_RSS_MB")
        if [[ $flow == *-uncached ]] && ((c > CAPACITY && R[busy] == 0)); then
            FAIL+=("$flow c=$c: concurrency above the pool capacity $CAPACITY but no 503")
        fi
        if [[ $flow == *-uncached ]] && ((hits > 0)); then
            FAIL+=("$flow c=$c: $hits result-cache hits: the requests were not all distinct")
        fi
        ((R[ok] > 0)) || FAIL+=("$flow c=$c: no successful response")
        unset R
    done
done

# --- the report -------------------------------------------------------------------------------
{
    echo "# grade3d load test"
    echo
    echo "- date: $(date -u +%Y-%m-%dT%H:%M:%SZ); binary: \`$BIN\`; commit: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
    echo "- machine: $(nproc) CPUs, $(awk '/MemTotal/ { printf "%.0f GiB", $2 / 1048576 }' /proc/meminfo); readyz: \`$READY\`"
    echo "- $DURATION s per run, wrk $(wrk -v 2>&1 | head -1 | awk '{ print $2 }') (nice 10); pool capacity $CAPACITY (workers $WORKERS + queue $QUEUE_DEPTH)"
    echo "- req/s counts every response (503s included), 2xx/s only successes; p50/p99 over all responses; cache hits: result-cache hits on the server during the run"
    echo "- peak RSS: the server's VmHWM during the run (reset before it) or the highest polled VmRSS; end RSS: VmRSS after the run"
    echo
    echo "| flow | conc. | req/s | 2xx/s | p50 | p99 | 2xx | 503 | other non-2xx | socket errors | cache hits | peak RSS MB | end RSS MB |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    printf '%s\n' "${ROWS[@]}"
    echo
    if ((${#FAIL[@]})); then
        echo "**FAILED**:"
        printf -- '- %s\n' "${FAIL[@]}"
    else
        echo "All checks passed: every response 2xx or 503, no socket errors, peak RSS within $MAX_RSS_MB MB."
    fi
} >"$WORK/report.md"
mkdir -p "$(dirname "$REPORT")"
cp "$WORK/report.md" "$REPORT"
echo
cat "$REPORT"
echo "(written to $REPORT)" >&2
((${#FAIL[@]} == 0)) || exit 1
