#!/usr/bin/env bash
# Builds Release and runs every benchmark (ncrev and, when installed, OpenMesh and CGAL in the
# same binary), 3 repetitions, medians; JSON beside the text. Takes about 25 minutes: the
# segmentation rows run once per repetition and the paper method needs 1.5 min at 5M facets;
# --benchmark_filter narrows it.
# Usage: bench/run.sh [OUT_PREFIX] [--benchmark_filter=REGEX]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-bench-results}
shift || true
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DNCREV_BUILD_BENCH=ON >/dev/null
cmake --build build -j"$(nproc)" --target ncrev_bench
build/bin/ncrev_bench --benchmark_min_time=1 --benchmark_repetitions=3 \
    --benchmark_report_aggregates_only=true --benchmark_out="$out.json" \
    --benchmark_out_format=json "$@" | tee "$out.txt"
