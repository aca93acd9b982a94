#!/usr/bin/env bash
# Installs the dependencies, builds ncrev (Release) and runs the main job on the bundled
# example: until surface recognition lands, that is `ncrev info` — what was read and what
# healing did — on a machined part from `ncrev sample`, as STL and as SRE.
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
echo "\$ build/bin/ncrev info --json examples/pocket_block.sre"
build/bin/ncrev info --json examples/pocket_block.sre
