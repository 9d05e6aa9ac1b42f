#!/usr/bin/env bash
# Fuzzing (docs/fuzzing.md): builds the libFuzzer targets with clang under AddressSanitizer + UndefinedBehaviorSanitizer
# in build-fuzz/ and runs them, two at a time (each fuzzer is one process on one core).
#   scripts/fuzz.sh [SECONDS] [TARGET...]    each target for SECONDS (default 600); targets: scene_loader obj_loader
#                                            hull_builder world (default: all four)
# FUZZ_SEED=N fixes libFuzzer's seed (CI's runs, so that what CI finds is found again by the same command); without
# it every run draws its own.
# Inputs that reach new code are kept in build-fuzz/corpus/TARGET (seeded from tests/data/fuzz/TARGET and the test
# scenes and OBJ files), so a later run goes on from there. An input that breaks a target is written to
# build-fuzz/findings/ and the script fails, printing the end of that target's log; once fixed, add the input to
# tests/data/fuzz/TARGET so that every build replays it (the Fuzz.*.Corpus tests).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-600}
[[ $seconds =~ ^[0-9]+$ ]] || { echo "fuzz.sh: SECONDS must be a whole number, got '$seconds'" >&2; exit 2; }
shift || true
all=(scene_loader obj_loader hull_builder world)
targets=("$@")
((${#targets[@]})) || targets=("${all[@]}")
for t in "${targets[@]}"; do
  [[ " ${all[*]} " == *" $t "* ]] || { echo "fuzz.sh: no target '$t' (targets: ${all[*]})" >&2; exit 2; }
done

scripts/install-deps.sh
CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DRUBBLE_WERROR=ON \
  -DRUBBLE_SANITIZE=address -DRUBBLE_FUZZ=ON -DRUBBLE_BUILD_TESTS=OFF -DRUBBLE_BUILD_APPS=OFF \
  -DRUBBLE_BUILD_PERF=OFF -DRUBBLE_BUILD_VIEWER=OFF >/dev/null
cmake --build build-fuzz --target "${targets[@]/#/rubble_fuzz_}"

# Per target: seed directories beyond its own, a dictionary, and the longest input worth mutating.
declare -A seeds=([scene_loader]="tests/data/scenes scenes" [obj_loader]="tests/data/obj")
declare -A dicts=([scene_loader]=fuzz/scene_loader.dict [obj_loader]=fuzz/obj_loader.dict)
declare -A lengths=([scene_loader]=16384 [obj_loader]=4096 [hull_builder]=8192 [world]=2048)
mkdir -p build-fuzz/findings build-fuzz/logs
run() {
  local t=$1 corpus=build-fuzz/corpus/$1
  mkdir -p "$corpus"
  # shellcheck disable=SC2086  # the seed directories are words
  build-fuzz/fuzz/rubble_fuzz_"$t" "$corpus" tests/data/fuzz/"$t" ${seeds[$t]:-} \
    ${dicts[$t]:+-dict=${dicts[$t]}} -max_len="${lengths[$t]}" -max_total_time="$seconds" -timeout=30 \
    -rss_limit_mb=4096 -print_final_stats=1 -artifact_prefix=build-fuzz/findings/"$t"- ${FUZZ_SEED:+-seed=$FUZZ_SEED} \
    >build-fuzz/logs/"$t".log 2>&1
}
failed=()
pids=()
names=()
wait_one() {
  local pid=${pids[0]} t=${names[0]}
  pids=("${pids[@]:1}") names=("${names[@]:1}")
  if wait "$pid"; then
    echo "fuzz $t: $(grep -E '^stat::number_of_executed_units' build-fuzz/logs/"$t".log | grep -oE '[0-9]+$') runs" \
      "in ${seconds} s, nothing found"
  else
    echo "fuzz $t: FAILED (input in build-fuzz/findings/, log build-fuzz/logs/$t.log):"
    tail -40 build-fuzz/logs/"$t".log
    failed+=("$t")
  fi
}
for t in "${targets[@]}"; do
  ((${#pids[@]} < 2)) || wait_one
  run "$t" &
  pids+=("$!") names+=("$t")
done
while ((${#pids[@]})); do wait_one; done
((${#failed[@]} == 0)) || { echo "fuzz.sh: findings in ${failed[*]}" >&2; exit 1; }
