#!/usr/bin/env bash
# schemathesis against openapi.yaml with the server running (issue #6):
# starts the binary given as $1 (default target/release/grade3d) on a free
# port with a fresh data folder and an API key, waits for /readyz, runs
# schemathesis with the checks below and at least 1,000 generated cases,
# and stops the server. Exits non-zero when schemathesis finds a failure.
# Run by tests/service.rs (required in CI); by hand:
#   pip install schemathesis && tests/schemathesis.sh target/release/grade3d
set -euo pipefail
cd "$(dirname "$0")/.."
BIN="${1:-target/release/grade3d}"
ST="${ST:-st}"
command -v "$ST" >/dev/null 2>&1 || ST="python3 -m schemathesis.cli"
KEY="schemathesis-key"
DATA="$(mktemp -d)"
PORT="$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')"
REPORTS="${SCHEMATHESIS_REPORTS:-target/schemathesis}"
mkdir -p "$REPORTS"
GRADE3D_API_KEY="$KEY" RUST_LOG=warn "$BIN" serve --addr "127.0.0.1:$PORT" --data-dir "$DATA" \
  --request-timeout-s 60 >"$REPORTS/server.log" 2>&1 &
PID=$!
trap 'kill "$PID" 2>/dev/null || true; wait "$PID" 2>/dev/null || true; rm -rf "$DATA"' EXIT
for _ in $(seq 600); do
  curl -fsS "http://127.0.0.1:$PORT/readyz" >/dev/null 2>&1 && break
  kill -0 "$PID" 2>/dev/null || { echo "server exited"; cat "$REPORTS/server.log"; exit 1; }
  sleep 0.1
done
# 15 operations x 70 examples (+ the coverage and stateful phases) > 1,000 cases
$ST run openapi.yaml --url "http://127.0.0.1:$PORT" \
  --checks not_a_server_error,response_schema_conformance,content_type_conformance,status_code_conformance,response_headers_conformance \
  --max-examples "${MAX_EXAMPLES:-70}" --seed 42 --workers 1 --request-timeout 120 \
  -H "Authorization: Bearer $KEY" \
  --suppress-health-check all \
  --report ndjson --report-dir "$REPORTS" \
  --no-color
status=$?
# the server must still be alive after it
kill -0 "$PID" 2>/dev/null || { echo "the server died during the run"; exit 1; }
exit $status
