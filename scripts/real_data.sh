#!/usr/bin/env bash
# Runs propid's identification over every dataset in ../shared/data (relative to the project
# root; override with PROPID_SHARED_DATA) and writes its Markdown table into docs/real_data.md
# between <!-- BEGIN real_data --> and <!-- END real_data --> (scripts/splice_docs.py). The
# table is produced here, never typed by hand.
#
#   scripts/real_data.sh            # into docs/real_data.md, between the markers
#   scripts/real_data.sh OUT.md     # the whole page to OUT.md instead
set -euo pipefail
cd "$(dirname "$0")/.."
data="${PROPID_SHARED_DATA:-../shared/data}"
out="${1:-}"
if [ ! -d "$data" ]; then
    echo "real_data.sh: $data is absent: skipped (the datasets live beside the project, see docs/real_data.md)"
    exit 0
fi
if [ -n "$out" ]; then
    cargo run --release --quiet --example real_data -- "$data" "$out"
    exit 0
fi
page="$(mktemp)"
trap 'rm -f "$page"' EXIT
cargo run --release --quiet --example real_data -- "$data" "$page"
python3 scripts/splice_docs.py real_data docs/real_data.md "$page"
