#!/usr/bin/env bash
# Issue 31's measurements, two builds paired in one run: `identify` of a 4 000- and a
# 100 000-sample pulse record, `identify` of a one-hour 1 kHz TSP/1 recording, `replay` of it,
# and (DAY=1) `replay` of a day-long one. Whole process each, wall time and peak memory
# ("Maximum resident set size") and CPU time (user + system) from /usr/bin/time -v; the two
# binaries run in turn (A B A B ...), RUNS times each; prints per case the median of each and
# the median of the pairwise CPU ratios A/B (on a loaded machine the wall times say little).
# Not run by CI; the numbers are in docs/speed.md.
#
#   scripts/bench_speed.sh NEW_BIN OLD_BIN [RUNS]     (RUNS default 3)
#
# Records (made here, nothing committed): the pulse records of scripts/identify_scale.sh (a
# 20 Hz, ζ 0.3 plant at 1 kHz, one one-sample pulse); the hour: `NEW_BIN sim --record` with
# config/sim.toml's plan at 4 790 pulses a level (3 600 s, ~146 MB); the day: 24 copies of the
# hour end to end (~3.5 GB, each a new boot of the device: the daemon starts a new segment).
# CASES="id4k id100k idhour hour day" picks cases (default: all but day, or all with DAY=1).
set -euo pipefail
cd "$(dirname "$0")/.."
new="$(realpath "$1")"
old="$(realpath "$2")"
runs="${3:-3}"
work="${WORK:-$(mktemp -d)}"
[ -n "${WORK:-}" ] || trap 'rm -rf "$work"' EXIT
cases="${CASES:-id4k id100k idhour hour${DAY:+ day}}"

pulse() { # samples, file
    awk -v n="$1" 'BEGIN {
        pi = atan2(0, -1); dt = 0.001; w = 2 * pi * 20; z = 0.3;
        r = exp(-z * w * dt); th = w * sqrt(1 - z * z) * dt;
        a1 = 2 * r * cos(th); a2 = -r * r; b = (1 - a1 - a2) / 2;
        print "t_s,throttle_us,thrust_N";
        for (k = 0; k < n; k++) { u[k] = (k == 100) ? 1500 : 1300; un[k] = (u[k] - 1000) / 1000 }
        y[0] = un[0]; y[1] = un[0];
        for (k = 2; k < n; k++) y[k] = a1 * y[k-1] + a2 * y[k-2] + b * (un[k-1] + un[k-2]);
        for (k = 0; k < n; k++) printf "%.6f,%.3f,%.12f\n", k * dt, u[k], y[k];
    }' > "$2"
}

hour="$work/hour.tsp"
need_hour() {
    [ -s "$hour" ] && return
    sed 's/^pulses_per_level = .*/pulses_per_level = 4790/' config/sim.toml > "$work/sim.toml"
    "$new" sim --config "$work/sim.toml" --record "$hour" --seconds 3600 > /dev/null
}

# One timed run: wall seconds, peak KB and CPU seconds on stdout.
timed() {
    local t0 t1
    t0=$(date +%s%N)
    /usr/bin/time -v "$@" > /dev/null 2> "$work/time.txt" || true
    t1=$(date +%s%N)
    awk -v a="$t0" -v b="$t1" -F': ' '/Maximum resident set size/ {kb = $2}
        /User time/ {u = $2} /System time/ {s = $2}
        END {printf "%.3f %d %.3f\n", (b - a) / 1e9, kb, u + s}' "$work/time.txt"
}

median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

bench() { # name, then the arguments after the binary
    local name="$1"
    shift
    : > "$work/a" && : > "$work/b" && : > "$work/r"
    for _ in $(seq "$runs"); do
        read -r wa ma ca < <(timed "$new" "$@")
        read -r wb mb cb < <(timed "$old" "$@")
        echo "$wa $ma $ca" >> "$work/a"
        echo "$wb $mb $cb" >> "$work/b"
        awk -v a="$ca" -v b="$cb" 'BEGIN {print (b > 0) ? a / b : 0}' >> "$work/r"
    done
    printf '%-26s new %8.3f s CPU %8.3f s wall %8.1f MB | old %8.3f s CPU %8.3f s wall %8.1f MB | new/old CPU %.3f\n' "$name" \
        "$(cut -d' ' -f3 "$work/a" | median)" "$(cut -d' ' -f1 "$work/a" | median)" "$(cut -d' ' -f2 "$work/a" | median | awk '{print $1 / 1024}')" \
        "$(cut -d' ' -f3 "$work/b" | median)" "$(cut -d' ' -f1 "$work/b" | median)" "$(cut -d' ' -f2 "$work/b" | median | awk '{print $1 / 1024}')" \
        "$(median < "$work/r")"
}

echo "# $runs paired runs each, medians; new $new, old $old; load $(cut -d' ' -f1-3 /proc/loadavg)"
for c in $cases; do
    case "$c" in
    id4k)
        pulse 4000 "$work/p4k.csv"
        bench "identify 4 000 samples" identify "$work/p4k.csv" --hankel square --order 2 --json ;;
    id100k)
        pulse 100000 "$work/p100k.csv"
        bench "identify 100 000 samples" identify "$work/p100k.csv" --hankel square --order 2 --json ;;
    idhour)
        need_hour
        bench "identify 1 h recording" identify "$hour" --json ;;
    hour)
        need_hour
        bench "replay 1 h recording" replay "$hour" ;;
    day)
        need_hour
        [ -s "$work/day.tsp" ] || for _ in $(seq 24); do cat "$hour"; done > "$work/day.tsp"
        bench "replay 24 h recording" replay "$work/day.tsp" ;;
    esac
done
