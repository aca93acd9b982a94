#!/usr/bin/env bash
# Installs the dependencies, builds ncrev (Release) and runs the main job on the bundled
# example, a machined part from `ncrev sample`: `ncrev info` (what was read and what healing
# did), then `ncrev reverse` to a STEP solid with planar faces merged (surface recognition —
# cylinders, cones, tori — is still to come).
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ "${NCREV_SKIP_INSTALL:-0}" != "1" ]]; then
    bash scripts/install-deps.sh
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target ncrev_cli
echo
echo "\$ build/bin/ncrev info examples/pocket_block.stl"
build/bin/ncrev info examples/pocket_block.stl
echo
echo "\$ build/bin/ncrev reverse examples/pocket_block.stl -o out/pocket_block.step --method planar --report out/pocket_block.report.json"
mkdir -p out
build/bin/ncrev reverse examples/pocket_block.stl -o out/pocket_block.step --method planar \
    --report out/pocket_block.report.json
echo "STEP written to out/pocket_block.step; report in out/pocket_block.report.json"
