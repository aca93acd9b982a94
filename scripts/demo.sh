#!/usr/bin/env bash
# Installs the dependencies, builds ncrev (Release) and runs the main job on the bundled
# example, a machined part from `ncrev sample`: `ncrev info` (what was read and what healing
# did), then `ncrev reverse` to the exact STEP solid: its 27 true faces (15 planes, 8
# cylinders, 4 tori), exact edges, colored by surface kind.
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
echo "\$ build/bin/ncrev reverse examples/pocket_block.stl -o out/pocket_block.step --report out/pocket_block.report.json"
mkdir -p out
build/bin/ncrev reverse examples/pocket_block.stl -o out/pocket_block.step \
    --report out/pocket_block.report.json
echo "STEP written to out/pocket_block.step; report in out/pocket_block.report.json"
