#!/usr/bin/env bash
# Peak memory of `propid identify --json` on a large CSV file, against the file's size (issue 27
# item 17): "Maximum resident set size" from /usr/bin/time -v, one process per file. Not run by
# CI; the numbers are in docs/identify.md ("Memory").
#
#   scripts/identify_memory.sh [BIN] [MB]      (default: target/release/propid, 100 MB)
#
# LOAD_ONLY=1: the file's loading alone (`--hankel` larger than any record, so that the
# identification refuses before it sizes a buffer; exit 4, no model).
#
# Two generated files of about MB megabytes each (nothing is committed), a step log at 1 kHz
# (a first-order thrust response, 0.1 s time constant, to command steps every 2 s, with noise):
# - narrow: `t_s,throttle_us,thrust_N` (~20 bytes a row);
# - wide: an export's 7 columns, `Time (s),ESC signal (µs),Thrust (N),Torque (N·m),Motor
#   Electrical Speed (RPM),Voltage (V),Current (A)` (~46 bytes a row), six of them read.
set -euo pipefail
cd "$(dirname "$0")/.."
bin="$(realpath "${1:-target/release/propid}")"
mb="${2:-100}"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

gen() { # shape, rows
    awk -v shape="$1" -v n="$2" 'BEGIN {
        srand(7); y = 0; a = exp(-0.001 / 0.1);
        if (shape == "narrow") print "t_s,throttle_us,thrust_N";
        else print "Time (s),ESC signal (µs),Thrust (N),Torque (N·m),Motor Electrical Speed (RPM),Voltage (V),Current (A)";
        for (k = 0; k < n; k++) {
            u = 1300 + 100 * (int(k / 2000) % 5);
            y = a * y + (1 - a) * (u - 1000) / 100;
            thrust = y + 0.01 * (rand() - 0.5);
            if (shape == "narrow") printf "%.3f,%d,%.4f\n", k / 1000, u, thrust;
            else printf "%.3f,%d,%.4f,%.5f,%d,%.3f,%.2f\n", k / 1000, u, thrust,
                0.02 * thrust, 3000 + 2000 * y, 16.4 - 0.05 * y, 2 * y;
        }
    }'
}

for shape in narrow wide; do
    f="$tmp/$shape.csv"
    per=$([ "$shape" = narrow ] && echo 20 || echo 46)
    gen "$shape" $((mb * 1000000 / per)) > "$f"
    size=$(stat -c %s "$f")
    rows=$(($(wc -l < "$f") - 1))
    t0=$(date +%s%N)
    extra=()
    [ -n "${LOAD_ONLY:-}" ] && extra=(--hankel 100000000x100000000)
    /usr/bin/time -v "$bin" identify --json "$f" "${extra[@]}" > "$tmp/out.json" 2> "$tmp/time.txt" || true
    t1=$(date +%s%N)
    kb=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$tmp/time.txt")
    awk -v s="$shape" -v size="$size" -v rows="$rows" -v kb="$kb" -v ms=$(((t1 - t0) / 1000000)) \
        'BEGIN { printf "%-6s %7.1f MB, %8d rows | peak RSS %7.1f MB = %.2f x the file, %.0f bytes a row | %.1f s\n",
            s, size / 1e6, rows, kb * 1024 / 1e6, kb * 1024 / size, kb * 1024 / rows, ms / 1000 }'
    [ -n "${LOAD_ONLY:-}" ] || grep -q '"model":{' "$tmp/out.json" || echo "  no model"
done
