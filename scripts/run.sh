#!/usr/bin/env bash
# The main job: install what is missing, build in Release, run the default scene (S1) and print its profile.
# Extra arguments go to `rubble run` (e.g. scripts/run.sh scenes/s4_sparse.json --threads 2).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target rubble_runner
if (($#)); then exec build/apps/rubble run "$@"; fi
exec build/apps/rubble run scenes/s1_pyramid.json --steps 60 --profile
