#!/usr/bin/env bash
# Recording helper: record a stand's raw TSP/1 byte stream while the daemon runs it, so the run
# can be replayed (`propid replay FILE`) or identified offline (`propid identify FILE`).
#
#   scripts/record.sh [PORT] [SECONDS] [OUT]
#     PORT     serial device (default /dev/propid-stand)
#     SECONDS  stop after this long (default 60; the daemon sends STOP and exits cleanly)
#     OUT      recording file (default recordings/<date>-<time>.tsp); the published JSON lines
#              go next to it as OUT.jsonl
#
# Without a stand: `propid sim --record run.tsp --seconds 60` writes a simulated recording.
set -euo pipefail
port="${1:-/dev/propid-stand}"
seconds="${2:-60}"
out="${3:-recordings/$(date -u +%Y%m%d-%H%M%S).tsp}"
propid="${PROPID:-propid}"
if ! command -v "$propid" >/dev/null 2>&1; then
    propid="$(dirname "$0")/../target/release/propid"
fi
mkdir -p "$(dirname "$out")"
cfg="$(mktemp)"
trap 'rm -f "$cfg"' EXIT
printf '[daemon]\nmax_run_s = %s\n[publish]\nfile = "%s"\n' "$seconds" "$out.jsonl" > "$cfg"
echo "recording $port for ${seconds}s into $out (models: $out.jsonl)" >&2
"$propid" run --config "$cfg" --port "$port" --record "$out"
echo "done: $(wc -c < "$out") bytes; replay with: $propid replay $out" >&2
