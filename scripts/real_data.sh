#!/usr/bin/env bash
# Runs propid's identification over every dataset in ../shared/data (relative to the project
# root; override with PROPID_SHARED_DATA) and writes the Markdown table docs/real_data.md that
# README shows. The table is produced here, never typed by hand.
#
#   scripts/real_data.sh            # writes docs/real_data.md
#   scripts/real_data.sh OUT.md     # writes elsewhere
set -euo pipefail
cd "$(dirname "$0")/.."
data="${PROPID_SHARED_DATA:-../shared/data}"
out="${1:-docs/real_data.md}"
if [ ! -d "$data" ]; then
    echo "real_data.sh: $data is absent: skipped (the datasets live beside the project, see README)"
    exit 0
fi
cargo run --release --quiet --example real_data -- "$data" "$out"
