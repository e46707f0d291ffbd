#!/usr/bin/env bash
# Runs the same chains in GStreamer and in fba, in one run, and prints the cost per extra
# element/hop and the ratios.
#   tools/gst-compare.sh [BUILD_DIR]      (default build/release)
# GStreamer: fakesrc num-buffers=N ! identity x K ! fakesink, in one thread, and with a queue
# before each identity (one thread per queue). fba: tools/runtime-benchmark, K passthroughs.
set -euo pipefail
build=${1:-build/release}
bench=$build/bin/fba-runtime-benchmark
command -v gst-launch-1.0 >/dev/null || { echo "gst-launch-1.0 missing: apt-get install gstreamer1.0-tools" >&2; exit 2; }
[ -x "$bench" ] || { echo "$bench missing: build first (tools/dev.sh test or cmake --build $build)" >&2; exit 2; }

# seconds for one gst-launch run; best of 3
gst_time() {
  local k=$1 n=$2 element=$3 best=""
  local pipeline="fakesrc num-buffers=$n"
  for ((i = 0; i < k; i++)); do pipeline+=" ! $element"; done
  pipeline+=" ! fakesink"
  for rep in 1 2 3; do
    local t0 t1
    t0=$(date +%s%N)
    # shellcheck disable=SC2086
    gst-launch-1.0 -q $pipeline >/dev/null
    t1=$(date +%s%N)
    local t=$((t1 - t0))
    if [ -z "$best" ] || [ "$t" -lt "$best" ]; then best=$t; fi
  done
  echo "$best"
}

per_hop() {  # element n -> ns per extra element from K=1 to K=50
  local t1 t50
  t1=$(gst_time 1 "$2" "$1")
  t50=$(gst_time 50 "$2" "$1")
  echo "scale=1; ($t50 - $t1) / 49 / $2" | bc
}

echo "== GStreamer $(gst-launch-1.0 --version | head -1 | awk '{print $NF}')"
gst_one=$(per_hop identity 200000)
gst_queue=$(per_hop "queue ! identity" 50000)
echo "gst per extra identity, one thread:          $gst_one ns"
echo "gst per extra queue+identity, threads:       $gst_queue ns"

echo "== fba ($bench)"
json=$("$bench" --json)
get() { echo "$json" | sed -n "s/.*\"$1\": \([0-9.]*\).*/\1/p"; }
fba_det=$(get "deterministic per extra hop (K=1..50)")
fba_thr=$(get "threaded per extra hop (K=1..50)")
fba_lat=$(get "threaded latency K=10 median per hop (1 kHz)")
fba_build=$(get "build a task of 1000 components")
echo "fba per extra hop, deterministic executor:   $fba_det ns"
echo "fba per extra hop, threaded, lossless:       $fba_thr ns"
echo "fba median latency per threaded hop, 1 kHz:  $fba_lat us"
echo "fba build of a 1000-component task:          $fba_build ms"

echo "== ratios (fba / GStreamer; target: <= 1 in one thread, <= 0.33 across threads)"
echo "one thread:    $(echo "scale=3; $fba_det / $gst_one" | bc)"
echo "across threads: $(echo "scale=3; $fba_thr / $gst_queue" | bc)"
echo "latency per threaded hop vs GStreamer's ~15 us: $(echo "scale=3; $fba_lat / 15" | bc)   (target: under 5 us)"
