#!/usr/bin/env bash
# The test job (what CI runs): install what is missing, check formatting, build everything with warnings as
# errors, run the whole test suite.
# RUBBLE_SANITIZE=address or RUBBLE_SANITIZE=thread in the environment runs the suite under that sanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/check-format.sh
sanitize=${RUBBLE_SANITIZE:-}
build=build${sanitize:+-$sanitize}
type=Release; [[ -n $sanitize ]] && type=RelWithDebInfo
# Benchmarks are timed only in a plain build; a sanitized one would compile them for nothing (6% of its build).
perf=ON; [[ -n $sanitize ]] && perf=OFF
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=$type -DRUBBLE_WERROR=ON -DRUBBLE_SANITIZE="$sanitize" \
    -DRUBBLE_BUILD_PERF=$perf >/dev/null
cmake --build "$build"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
