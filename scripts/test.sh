#!/usr/bin/env bash
# Installs the dependencies, builds with warnings as errors, runs every test, runs each fuzzer
# briefly, and runs the tests again under AddressSanitizer + UndefinedBehaviorSanitizer.
# Environment: NCREV_FUZZ_SECONDS (default 20 per fuzzer), NCREV_SKIP_SANITIZERS=1,
# NCREV_SKIP_FUZZ=1, NCREV_SKIP_INSTALL=1 (for a machine already set up).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc)
fuzz_seconds=${NCREV_FUZZ_SECONDS:-20}

if [[ "${NCREV_SKIP_INSTALL:-0}" != "1" ]]; then
    bash scripts/install-deps.sh
fi

echo "== format (.clang-format)"
git ls-files '*.cpp' '*.h' | xargs clang-format --dry-run --Werror

echo "== build (Release, warnings as errors)"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DNCREV_WERROR=ON >/dev/null
cmake --build build -j"$jobs"

echo "== tests"
ctest --test-dir build --output-on-failure -j"$jobs"

if [[ "${NCREV_SKIP_FUZZ:-0}" != "1" ]]; then
    echo "== fuzzers (${fuzz_seconds} s each, clang + libFuzzer + ASan/UBSan)"
    cmake -S . -B build-fuzz -DNCREV_FUZZ=ON -DNCREV_WERROR=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCMAKE_CXX_COMPILER=clang++-14 >/dev/null
    cmake --build build-fuzz -j"$jobs"
    for target in stl_reader sre_reader mesh_build; do
        work=$(mktemp -d)
        cp -r "fuzz/seeds/${target}/." "$work/" 2>/dev/null || true
        # The bundled binary STL serves as a binary seed (libFuzzer cuts it to -max_len).
        [[ "$target" == stl_reader ]] && cp examples/pocket_block.stl "$work/"
        echo "-- fuzz_${target}"
        log=$(mktemp)
        if ! ./build-fuzz/bin/fuzz_${target} -max_total_time="$fuzz_seconds" -max_len=4096 \
            -print_final_stats=1 -artifact_prefix="$work/" "$work" >"$log" 2>&1; then
            tail -n 60 "$log"
            echo "fuzz_${target}: crash (artifact in $work)"
            exit 1
        fi
        grep -E "^stat::number_of_executed_units" "$log" || true
        rm -rf "$work" "$log"
    done
fi

if [[ "${NCREV_SKIP_SANITIZERS:-0}" != "1" ]]; then
    echo "== tests under ASan + UBSan (clang)"
    cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNCREV_SANITIZE=ON \
        -DNCREV_WERROR=ON -DNCREV_BUILD_BENCH=OFF -DCMAKE_CXX_COMPILER=clang++-14 >/dev/null
    cmake --build build-asan -j"$jobs"
    ASAN_OPTIONS=detect_leaks=1 LSAN_OPTIONS=suppressions="$PWD/tests/lsan.supp" \
        UBSAN_OPTIONS=print_stacktrace=1 \
        ctest --test-dir build-asan --output-on-failure -j"$jobs"
fi
echo "== all checks passed"
