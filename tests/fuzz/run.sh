#!/bin/sh
# Usage: run.sh BUILD_DIR SECONDS [RUNS [TARGET]]
# Fuzzes TARGET (task_loader, the default, or request_handling: the live view's server) for
# SECONDS, or until it has run RUNS inputs if that comes first, on a scratch copy of its seed
# corpus (corpus/ for the loader, corpus_TARGET/ for the others; the seeds in git stay as they
# are). Exits 2 when it cannot start (its arguments, no fuzzer built), non-zero otherwise on a
# finding (libFuzzer: 70, 77); libFuzzer writes the input to BUILD_DIR/fuzz-findings/ (the loader's)
# or BUILD_DIR/fuzz-findings-TARGET/, and this script copies it into the seed corpus as a
# regression case.
set -eu
if [ $# -lt 2 ] || [ $# -gt 4 ]; then
  echo "usage: $0 BUILD_DIR SECONDS [RUNS [TARGET]]" >&2
  exit 2
fi
build=$1
seconds=$2
runs=${3:--1}
target=${4:-task_loader}
case "$seconds" in '' | *[!0-9]*) echo "$0: SECONDS: expected a whole number of seconds, found '$seconds'" >&2; exit 2 ;; esac
case "$runs" in -1) ;; '' | *[!0-9]*) echo "$0: RUNS: expected a whole number of inputs, found '$runs'" >&2; exit 2 ;; esac
here=$(cd "$(dirname "$0")" && pwd)
case "$target" in
  task_loader) corpus=$here/corpus dict=$here/yaml.dict findings=$build/fuzz-findings ;;
  request_handling) corpus=$here/corpus_$target dict=$here/$target.dict findings=$build/fuzz-findings-$target ;;
  *) echo "$0: TARGET: expected task_loader or request_handling, found '$target'" >&2; exit 2 ;;
esac
fuzzer=$build/bin/fuzz_$target
if [ ! -x "$fuzzer" ]; then
  echo "$0: no $fuzzer; build the target fuzz_$target with FBA_BUILD_FUZZERS=ON (see tests/fuzz/CMakeLists.txt)" >&2
  exit 2
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$corpus"/* "$work"/
mkdir -p "$findings"
# -timeout: an input that takes 10 s is a hang, and a finding too.
status=0
"$fuzzer" -max_total_time="$seconds" -runs="$runs" -timeout=10 -dict="$dict" -print_final_stats=1 \
  -artifact_prefix="$findings/" "$work" || status=$?
# A finding joins the seed corpus, which the ctest fuzz_TARGET_seeds replays on every run: once
# fixed, it stays fixed. Commit it with the fix.
for f in "$findings"/crash-* "$findings"/timeout-* "$findings"/oom-* "$findings"/leak-*; do
  [ -e "$f" ] || continue
  cp "$f" "$corpus/finding-$(basename "$f")"
  echo "$0: saved $f as tests/fuzz/$(basename "$corpus")/finding-$(basename "$f")" >&2
done
exit $status
