#!/usr/bin/env bash
# Produces the detection table of `propid diagnose` (issue 5) and the real-data table, and puts
# both into docs/detection.md between the markers
#   <!-- BEGIN detection --> ... <!-- END detection -->   (scripts/splice_docs.py)
# Nothing in those tables is typed by hand.
#
# Usage: [PROPID_SHARED_DATA=DIR] scripts/detection_table.sh [CASES] [DATA_DIR]
#   CASES     seeded synthetic cases per effect (default 20; clean cases: max(CASES, 50))
#   DATA_DIR  the real datasets; else $PROPID_SHARED_DATA; else ../shared/data relative to the
#             project root (skipped with a message when absent). A relative DATA_DIR or
#             PROPID_SHARED_DATA is taken relative to the directory the script is called from.
# Slow in a loaded machine: run it with `nice` (it builds and runs in release).
set -euo pipefail
caller="$(pwd)"
cd "$(dirname "$0")/.."
cases="${1:-20}"
data="${2:-${PROPID_SHARED_DATA:-}}"
if [ -z "$data" ]; then
    data="$(pwd)/../shared/data"
elif [ "${data#/}" = "$data" ]; then
    data="$caller/$data"
fi
data="$(realpath -m "$data")" # the table names the folder without ../ detours
if [ ! -d "$data" ]; then
    echo "warning: data dir $data absent; the real-data table will say so" >&2
fi
doc=docs/detection.md
table="$(mktemp)"
trap 'rm -f "$table"' EXIT
cargo run --quiet --release --example detection_table -- "$cases" "$data" > "$table"
{
    echo
    echo "_Produced by \`scripts/detection_table.sh $cases\` on $(date -u +%Y-%m-%d)._"
    echo
    cat "$table"
    echo
} | python3 scripts/splice_docs.py detection "$doc"
