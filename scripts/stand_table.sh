#!/usr/bin/env bash
# Produces the simulated-stand tables of `propid diagnose` (issue 29 items 4 and 6: hidden
# effects under pulse, step and staircase records, under- and overdamped stands, and the
# false alarms on clean stands) and puts them into docs/detection.md between the markers
#   <!-- BEGIN stand --> ... <!-- END stand -->              (2nd-order plants, thrust only)
#   <!-- BEGIN stand_motor --> ... <!-- END stand_motor -->  (motor stands: rpm, thrust, current)
# (scripts/splice_docs.py). Nothing in those tables is typed by hand.
#
# Usage: scripts/stand_table.sh [CASES] [THREADS] [motor [BUDGET_S]]   (per effect and record kind;
#   default 7: 21 per effect over the three kinds, and 21 clean stands; THREADS default 2, the
#   machine's cores; `motor`: the motor stands' table. A 2nd-order case took 45–60 s of wall
#   time per thread on the 2-core machine under a load of ~18: CASES 7 is 231 cases; the
#   motor table prints its own mean time per case; with BUDGET_S no motor case starts after
#   that many seconds, and the table's header says how many ran.)
# Slow in a loaded machine: run it with `nice` (it builds and runs in release).
set -euo pipefail
cd "$(dirname "$0")/.."
cases="${1:-7}"
threads="${2:-2}"
which="${3:-}"
budget="${4:-inf}"
doc=docs/detection.md
table="$(mktemp)"
trap 'rm -f "$table"' EXIT
if [ "$which" = motor ]; then
    marker=stand_motor
    cargo run --quiet --release -p propid-diagnose --example stand_table -- "$cases" "$threads" rising motor "$budget" > "$table"
else
    marker=stand
    cargo run --quiet --release -p propid-diagnose --example stand_table -- "$cases" "$threads" > "$table"
fi
{
    echo
    echo "_Produced by \`scripts/stand_table.sh $cases $threads $which${which:+ $budget}\` on $(date -u +%Y-%m-%d)._"
    echo
    cat "$table"
    echo
} | python3 scripts/splice_docs.py "$marker" "$doc"
