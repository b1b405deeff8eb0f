#!/usr/bin/env bash
# Time and peak memory of the truncated Hankel SVD at 1 000, 4 000 and 100 000 samples (square
# Hankel, two leading triplets + U^T H(1) V), one process per size so that each peak is its own.
# Not run by CI. Targets (issue 6): 100 000 samples in well under 1 s and < 64 MB peak.
set -euo pipefail
cd "$(dirname "$0")/.."
for n in ${SIZES:-1000 4000 100000}; do
    cargo bench --quiet --bench svd_scale -- "$n"
done
