#!/usr/bin/env bash
# Fails when a C++ file is not formatted as .clang-format says (clang-format 14).
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.h' '*.cpp' 2>/dev/null || find include src simd tests perf apps -name '*.h' -o -name '*.cpp')
((${#files[@]})) || exit 0
clang-format --dry-run --Werror "${files[@]}"
