#!/usr/bin/env bash
# Installs every Debian 12 package that ncrev's build, tests, fuzzers and benchmarks need.
# Idempotent: running it again only refreshes the package lists and finds everything installed.
# Needs root (or sudo). Set NCREV_NO_PEERS=1 to skip the optional benchmark peers
# (OpenMesh, CGAL), which only bench/ uses.
set -euo pipefail

packages=(
    build-essential cmake ninja-build pkg-config git
    g++ clang-14 libclang-rt-14-dev clang-format  # clang: sanitizer build, libFuzzer; format check
    libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev
    libocct-data-exchange-dev libocct-ocaf-dev libocct-visualization-dev
    libeigen3-dev libtbb-dev libcli11-dev nlohmann-json3-dev
    libgtest-dev libgmock-dev libbenchmark-dev
)
if [[ "${NCREV_NO_PEERS:-0}" != "1" ]]; then
    packages+=(libopenmesh-dev libcgal-dev)    # benchmark peers (bench/ only)
fi

SUDO=""
if [[ "$(id -u)" != "0" ]]; then SUDO="sudo"; fi

export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${packages[@]}" >/dev/null
echo "install-deps: ${#packages[@]} packages present"
