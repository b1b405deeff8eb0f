#!/usr/bin/env bash
# Side-by-side benchmark (issue 6): python-control's `era` against `propid identify` on the same
# mass-spring-damper pulse record at 1 kHz, N = 1 000, 4 000 and 100 000 samples. Each is timed
# in one run: the `era` call alone for python-control, the whole `propid identify` process for
# propid. Prints times, their ratio and fn, zeta, DC gain of both against the truth.
#
# Not run by CI. Installs python-control, numpy and scipy into its own virtual environment
# (target/pyctl-venv) on first use; needs network access to PyPI then.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=target/pyctl-venv
OUT=target/bench_vs_python_control
if [ ! -x "$VENV/bin/python" ]; then
    python3 -m venv "$VENV"
    "$VENV/bin/pip" install --quiet --upgrade pip
    "$VENV/bin/pip" install --quiet control numpy scipy
fi
cargo build --release --quiet --bin propid
mkdir -p "$OUT"
# One BLAS thread, as in the issue's measurements.
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
for n in ${SIZES:-1000 4000 100000}; do
    csv="$OUT/msd_$n.csv"
    "$VENV/bin/python" scripts/compare_python_control.py generate "$n" "$csv"
    "$VENV/bin/python" scripts/compare_python_control.py compare "$csv" --propid target/release/propid
    echo
done
"$VENV/bin/python" -c "import control, numpy, scipy; print('python-control', control.__version__, 'numpy', numpy.__version__, 'scipy', scipy.__version__)"
