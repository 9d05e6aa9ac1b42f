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
if [[ -d $build/lib/glibc-hwcaps ]]; then
  # A dispatch build (one core per x86-64 level): the suite once per level this CPU runs, the loader's own choice
  # first, the others by hiding from it (and from the core's check) the features of the levels above.
  levels=$(/lib64/ld-linux-x86-64.so.2 --help | grep -oE 'x86-64-v[234] \(supported' | cut -d' ' -f1)
  # The hard cases' minute-long runs (HardCasesLong, about five minutes beside the suite) on the first level only.
  long=1
  for level in $levels; do
    case $level in
      x86-64-v4) hide= ;;
      x86-64-v3) hide=glibc.cpu.hwcaps=-AVX512F ;;
      x86-64-v2) hide=glibc.cpu.hwcaps=-AVX2,-AVX512F ;;
    esac
    echo "== the suite on the core built for $level"
    env RUBBLE_EXPECT_CORE_BUILD="$level" ${hide:+GLIBC_TUNABLES=$hide} RUBBLE_LONG_TESTS=$long \
      ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
    long=0
  done
else
  RUBBLE_LONG_TESTS=$([[ -z $sanitize ]] && echo 1 || echo 0) ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
fi
# The accuracy report's short run (about a minute), so that the command cannot rot; docs/ACCURACY.md comes from a
# full run (`build/apps/rubble accuracy --out docs`).
if [[ -z $sanitize ]]; then
  report=$(mktemp -d)
  "$build/apps/rubble" accuracy --quick --out "$report"
  rm -rf "$report"
fi
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
  c++ -std=c++20 examples/consumer/drop_box.cpp -o "$consumer/drop_box_pc" $(pkg-config --cflags --libs rubble) \
    -Wl,-rpath,"$consumer/prefix/lib"
  "$consumer/drop_box_pc"
fi
