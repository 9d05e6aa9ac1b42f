#!/usr/bin/env bash
# The AVX2 level of the core forced on a CPU that (as far as the loader and the library can tell) has no AVX2: the
# library must refuse with a message naming what is missing and exit 1, not die on an illegal instruction.
# Usage: cpu_refusal.sh RUNNER DIR_OF_THE_X86_64_V3_CORE
set -u
runner=$1
v3_dir=$2
if ! /lib64/ld-linux-x86-64.so.2 --help | grep -q 'x86-64-v3 (supported'; then
  echo "skipped: this CPU has no x86-64-v3 level to hide"
  exit 77
fi
out=$(LD_LIBRARY_PATH=$v3_dir GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2 "$runner" --help 2>&1)
rc=$?
echo "$out"
if [[ $rc -ne 1 ]]; then
  echo "FAIL: expected exit status 1, got $rc"
  exit 1
fi
if ! grep -q 'compiled for x86-64-v3 and needs AVX2,* ' <<<"$out"; then
  echo "FAIL: the message does not name the level and AVX2"
  exit 1
fi
