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
# The installed package, used from outside the tree: CMake (examples/consumer) and pkg-config.
if [[ -z $sanitize ]]; then
  consumer=$(mktemp -d)
  trap 'rm -rf "$consumer"' EXIT
  cmake --install "$build" --prefix "$consumer/prefix" >/dev/null
  cmake -S examples/consumer -B "$consumer/build" -G Ninja -DCMAKE_PREFIX_PATH="$consumer/prefix" >/dev/null
  cmake --build "$consumer/build" >/dev/null
  "$consumer/build/drop_box"
  export PKG_CONFIG_PATH="$consumer/prefix/lib/pkgconfig"
  # shellcheck disable=SC2046  # pkg-config's flags are words
  c++ -std=c++20 examples/consumer/drop_box.cpp -o "$consumer/drop_box_pc" $(pkg-config --cflags --libs rubble)
  "$consumer/drop_box_pc"
fi
