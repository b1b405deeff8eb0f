#!/usr/bin/env bash
# Produces the table of a load cell's lag hidden in a measured stand's thrust (issue 29 item 6:
# the vanderploeg 90PERCENT staircase from the shared data, every other channel kept) and puts
# it into docs/injection.md between the markers
#   <!-- BEGIN stand_lag --> ... <!-- END stand_lag -->   (scripts/splice_docs.py)
# In memory (crates/diagnose/examples/stand_lag_table.rs): about 6 s of CPU per draw.
#
# Usage: scripts/stand_lag_table.sh [DRAWS] [SHARED_DIR]   (default 10 draws; SHARED_DIR
#   default $PROPID_SHARED_DATA or ../shared/data)
set -euo pipefail
cd "$(dirname "$0")/.."
draws="${1:-10}"
shared="${2:-${PROPID_SHARED_DATA:-../shared/data}}"
file="$shared/vanderploeg-rcbenchmark-steps/90PERCENT_2024-08-13_185523.csv"
if [ ! -f "$file" ]; then
    echo "stand_lag_table: $file is absent (shared dataset)" >&2
    exit 1
fi
table="$(mktemp)"
trap 'rm -f "$table"' EXIT
cargo run --quiet --release -p propid-diagnose --example stand_lag_table -- "$file" "$draws" > "$table"
{
    echo
    echo "_Produced by \`scripts/stand_lag_table.sh $draws\` on $(date -u +%Y-%m-%d)._"
    echo
    cat "$table"
    echo
} | python3 scripts/splice_docs.py stand_lag docs/injection.md
