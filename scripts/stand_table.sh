#!/usr/bin/env bash
# Produces the simulated-stand table of `propid diagnose` (issue 29 items 4 and 6: hidden
# effects under pulse, step and staircase records, under- and overdamped stands, and the
# false alarms on clean stands) and puts it into docs/detection.md between the markers
#   <!-- BEGIN stand --> ... <!-- END stand -->   (scripts/splice_docs.py)
# Nothing in that table is typed by hand.
#
# Usage: scripts/stand_table.sh [CASES] [THREADS]   (per effect and record kind; default 7: 21
#   per effect over the three kinds, and 21 clean stands; THREADS default 2, the machine's cores.
#   A case took 45–60 s of wall time per thread on the 2-core machine under a load of ~18:
#   CASES 7 is 231 cases)
# Slow in a loaded machine: run it with `nice` (it builds and runs in release).
set -euo pipefail
cd "$(dirname "$0")/.."
cases="${1:-7}"
threads="${2:-2}"
doc=docs/detection.md
table="$(mktemp)"
trap 'rm -f "$table"' EXIT
cargo run --quiet --release -p propid-diagnose --example stand_table -- "$cases" "$threads" > "$table"
{
    echo
    echo "_Produced by \`scripts/stand_table.sh $cases\` on $(date -u +%Y-%m-%d)._"
    echo
    cat "$table"
    echo
} | python3 scripts/splice_docs.py stand "$doc"
