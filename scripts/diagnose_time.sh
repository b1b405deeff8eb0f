#!/usr/bin/env bash
# Times `propid diagnose` as a whole process (/usr/bin/time, the median of RUNS runs) on the
# bitcraze cf21 log (when ../shared/data is present) and on generated 1 kHz staircases of
# 20 000 and 60 000 samples: random levels 0.2..0.8 held 3 s, thrust 900 gf · u² through a 40 ms
# lag and a 10 ms dead time, deterministic noise. With a second binary, both in turn and the
# ratio of the medians. Numbers for docs/speed.md.
#
#   scripts/diagnose_time.sh BIN [OTHER_BIN] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin="$(realpath "$1")"
other="${2:-}"
runs="${3:-3}"
data="${PROPID_SHARED_DATA:-../shared/data}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT

staircase() { # samples, file
    awk -v n="$1" 'BEGIN {
        srand(7); dt = 0.001; a = exp(-dt / 0.04); y = 0; d = 10; lv = 0.5
        print "time_s,throttle_pct,thrust_g"
        for (k = 0; k < n; k++) {
            if (k % 3000 == 0) lv = 0.2 + 0.1 * int(7 * rand())
            u[k] = lv
            ud = (k >= d) ? u[k - d] : u[0]
            y = a * y + (1 - a) * 900 * ud * ud
            printf "%.4f,%.2f,%.2f\n", k * dt, 100 * lv, y + 2 * (rand() + rand() + rand() - 1.5)
        }
    }' >"$2"
}

median() { sort -g | awk '{v[NR] = $1} END {print v[int((NR + 1) / 2)]}'; }

timed() { # binary, args...
    local b="$1"
    shift
    for _ in $(seq "$runs"); do
        /usr/bin/time -f "%e" "$b" diagnose "$@" 2>&1 >/dev/null | tail -1
    done | median
}

cases=()
if [ -f "$data/bitcraze-cf21-pwm-steps/cf21_stock2.csv" ]; then
    cases+=("cf21|--fs 100 $data/bitcraze-cf21-pwm-steps/cf21_stock2.csv")
fi
for n in 20000 60000; do
    staircase "$n" "$dir/staircase_$n.csv"
    cases+=("staircase $n|$dir/staircase_$n.csv")
done
for c in "${cases[@]}"; do
    name="${c%%|*}"
    read -r -a args <<<"${c#*|}"
    a=$(timed "$bin" "${args[@]}")
    if [ -n "$other" ]; then
        b=$(timed "$(realpath "$other")" "${args[@]}")
        echo "$name: ${a} s, other ${b} s, ratio $(awk -v a="$a" -v b="$b" 'BEGIN {printf "%.2f", a / b}')"
    else
        echo "$name: ${a} s"
    fi
done
