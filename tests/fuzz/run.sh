#!/bin/sh
# Usage: run.sh BUILD_DIR SECONDS [RUNS]
# Fuzzes the task loader for SECONDS, or until it has run RUNS inputs if that comes first, on a
# scratch copy of the seed corpus (the seeds in git stay as they are). Exits 2 when it cannot start
# (its arguments, no fuzzer built), non-zero otherwise on a finding (libFuzzer: 70, 77); libFuzzer
# writes the input to BUILD_DIR/fuzz-findings/, and this script copies it into the seed corpus as a
# regression case.
set -eu
if [ $# -lt 2 ] || [ $# -gt 3 ]; then
  echo "usage: $0 BUILD_DIR SECONDS [RUNS]" >&2
  exit 2
fi
build=$1
seconds=$2
runs=${3:--1}
case "$seconds" in '' | *[!0-9]*) echo "$0: SECONDS: expected a whole number of seconds, found '$seconds'" >&2; exit 2 ;; esac
case "$runs" in -1) ;; '' | *[!0-9]*) echo "$0: RUNS: expected a whole number of inputs, found '$runs'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
fuzzer=$build/bin/fuzz_task_loader
if [ ! -x "$fuzzer" ]; then
  echo "$0: no $fuzzer; build the target fuzz_task_loader with FBA_BUILD_FUZZERS=ON (see tests/fuzz/CMakeLists.txt)" >&2
  exit 2
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$here"/corpus/* "$work"/
mkdir -p "$build/fuzz-findings"
# -timeout: an input that takes 10 s is a hang, and a finding too.
status=0
"$fuzzer" -max_total_time="$seconds" -runs="$runs" -timeout=10 -dict="$here/yaml.dict" -print_final_stats=1 \
  -artifact_prefix="$build/fuzz-findings/" "$work" || status=$?
# A finding joins the seed corpus, which the ctest fuzz_task_loader_seeds replays on every run:
# once fixed, it stays fixed. Commit it with the fix.
for f in "$build"/fuzz-findings/crash-* "$build"/fuzz-findings/timeout-* "$build"/fuzz-findings/oom-* \
         "$build"/fuzz-findings/leak-*; do
  [ -e "$f" ] || continue
  cp "$f" "$here/corpus/finding-$(basename "$f")"
  echo "$0: saved $f as tests/fuzz/corpus/finding-$(basename "$f")" >&2
done
exit $status
