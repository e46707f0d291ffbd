#!/usr/bin/env bash
# Runs the same chains in GStreamer and in fba, in one run, like with like, and prints wall and CPU
# time per extra element/hop, end-to-end latency at 1 kHz, and the ratios.
#   tools/gst-compare.sh [BUILD_DIR]      (default build/release)
# One thread:          GStreamer fakesrc ! identity x K ! fakesink      vs fba's deterministic executor,
#                      both as whole processes (gst-launch-1.0, fba-run) taken in turn, the least CPU
#                      of 5 rounds each (the target's figure), and fba in process (the benchmark's).
# A thread per element: GStreamer fakesrc ! (queue ! identity) x K ! fakesink
#                                                    vs fba with every component `thread: dedicated`.
# fba's pooled threaded executor (components share the workers) has no GStreamer counterpart and is
# reported on its own line. CPU time is the process's user + system time, all threads.
# Latency: GStreamer's own latency tracer (source pad to sink pad, every buffer) on a 1 kHz live
# source through 10 queue ! identity pairs, against fba's 10 dedicated hops fed at 1 kHz.
set -euo pipefail
build=${1:-build/release}
bench=$build/bin/fba-runtime-benchmark
command -v gst-launch-1.0 >/dev/null || { echo "gst-launch-1.0 missing: apt-get install gstreamer1.0-tools" >&2; exit 2; }
[ -x "$bench" ] || { echo "$bench missing: build first (tools/dev.sh test or cmake --build $build)" >&2; exit 2; }

# times_ns COMMAND... -> "wall_ns cpu_ns" of the child (bash's time keyword: real, user and system
# seconds, on stderr; CPU is user + system)
times_ns() {
  local times
  times=$( { TIMEFORMAT='%R %U %S'; time "$@" >/dev/null 2>&1; } 2>&1)
  echo "$times" | awk '{printf "%d %d\n", $1 * 1e9, ($2 + $3) * 1e9}'
}

# gst_run K N ELEMENT -> "wall_ns cpu_ns" of the best (by wall time) of 3 runs of
# fakesrc num-buffers=N ! ELEMENT x K ! fakesink
gst_run() {
  local k=$1 n=$2 element=$3 best_wall="" best_cpu=""
  local pipeline="fakesrc num-buffers=$n"
  for ((i = 0; i < k; i++)); do pipeline+=" ! $element"; done
  pipeline+=" ! fakesink"
  for _ in 1 2 3; do
    local wall cpu
    # shellcheck disable=SC2086
    read -r wall cpu < <(times_ns gst-launch-1.0 -q $pipeline)
    if [ -z "$best_wall" ] || [ "$wall" -lt "$best_wall" ]; then best_wall=$wall best_cpu=$cpu; fi
  done
  echo "$best_wall $best_cpu"
}

# per_hop ELEMENT N -> "wall_ns cpu_ns" per extra element from K=1 to K=50, per buffer
per_hop() {
  local one fifty
  one=$(gst_run 1 "$2" "$1")
  fifty=$(gst_run 50 "$2" "$1")
  echo "$one $fifty" | awk -v n="$2" '{printf "%.1f %.1f\n", ($3 - $1) / 49 / n, ($4 - $2) / 49 / n}'
}

# gst_latency K N -> "median_us p99_us" end to end, from the latency tracer, N buffers at 1 kHz
gst_latency() {
  local k=$1 n=$2
  local pipeline="videotestsrc is-live=true num-buffers=$n pattern=black ! video/x-raw,width=16,height=16,framerate=1000/1"
  for ((i = 0; i < k; i++)); do pipeline+=" ! queue ! identity"; done
  pipeline+=" ! fakesink"
  # shellcheck disable=SC2086
  GST_TRACERS=latency GST_DEBUG=GST_TRACER:7 GST_DEBUG_NO_COLOR=1 gst-launch-1.0 -q $pipeline 2>&1 >/dev/null |
    sed -n 's/.*latency, src-element-id.*time=(guint64)\([0-9]*\).*/\1/p' | sort -n |
    awk '{v[NR] = $1} END {
           if (NR == 0) { print "no latency records" > "/dev/stderr"; exit 1 }
           printf "%.1f %.1f\n", v[int(NR / 2) + 1] / 1000, v[int(NR * 99 / 100) + 1] / 1000 }'
}

ratio() { echo "$1 $2" | awk '{printf "%.3f", $1 / $2}'; }

# in_turn ROUNDS N -> "gst_cpu_ns fba_cpu_ns" per extra element, one thread, whole processes: K=1 and
# K=50 chains of each taken in turn ROUNDS times, the least CPU of each. A virtual machine's speed
# swings by half between runs a second apart; runs in turn see the same swings.
in_turn() {
  local rounds=$1 n=$2 dir k r
  dir=$(mktemp -d)
  for k in 1 50; do
    {
      echo "executor: deterministic"
      echo "components:"
      echo "  src: { type: examples.counter, params: { count: $n } }"
      for ((r = 0; r < k; r++)); do echo "  p$r: { type: examples.passthrough }"; done
      echo "  sink: { type: examples.sink, params: { expected: $n } }"
      echo "connections:"
      echo "  - src.out -> p0.in"
      for ((r = 1; r < k; r++)); do echo "  - p$((r - 1)).out -> p$r.in"; done
      echo "  - p$((k - 1)).out -> sink.in"
    } >"$dir/chain$k.yaml"
  done
  local -A least=()
  for ((r = 0; r < rounds; r++)); do
    for k in 1 50; do
      local pipeline="fakesrc num-buffers=$n" i t
      for ((i = 0; i < k; i++)); do pipeline+=" ! identity"; done
      # shellcheck disable=SC2086
      read -r _ t < <(times_ns gst-launch-1.0 -q $pipeline ! fakesink)
      [ -z "${least[gst$k]:-}" ] || [ "$t" -lt "${least[gst$k]}" ] && least[gst$k]=$t
      read -r _ t < <(times_ns "$build/bin/fba-run" "$dir/chain$k.yaml")
      [ -z "${least[fba$k]:-}" ] || [ "$t" -lt "${least[fba$k]}" ] && least[fba$k]=$t
    done
  done
  rm -rf "$dir"
  echo "${least[gst1]} ${least[gst50]} ${least[fba1]} ${least[fba50]}" |
    awk -v n="$n" '{printf "%.1f %.1f\n", ($2 - $1) / 49 / n, ($4 - $3) / 49 / n}'
}

echo "== GStreamer $(gst-launch-1.0 --version | head -1 | awk '{print $NF}')"
read -r gst_one gst_one_cpu < <(per_hop identity 200000)
read -r gst_queue gst_queue_cpu < <(per_hop "queue ! identity" 50000)
read -r gst_lat gst_lat_p99 < <(gst_latency 10 2000)
printf '%-58s %10s ns wall %10s ns CPU\n' "gst per extra identity, one thread:" "$gst_one" "$gst_one_cpu"
printf '%-58s %10s ns wall %10s ns CPU\n' "gst per extra queue ! identity, a thread each:" "$gst_queue" "$gst_queue_cpu"
printf '%-58s %10s us median %7s us p99\n' "gst latency, 10 queue ! identity, 1 kHz, end to end:" "$gst_lat" "$gst_lat_p99"

echo "== fba ($bench)"
json=$("$bench" --json)
get() {
  local v
  v=$(echo "$json" | sed -n "s/.*\"$1\": \([-0-9.]*\).*/\1/p")
  [ -n "$v" ] || { echo "no '$1' in the benchmark's output" >&2; exit 1; }
  echo "$v"
}
fba_det=$(get "deterministic per extra hop (K=1..50)")
fba_det_cpu=$(get "deterministic CPU per extra hop (K=1..50)")
fba_ded=$(get "dedicated per extra hop (K=1..50)")
fba_ded_cpu=$(get "dedicated CPU per extra hop (K=1..50)")
fba_pool=$(get "pooled per extra hop (K=1..50)")
fba_pool_cpu=$(get "pooled CPU per extra hop (K=1..50)")
fba_lat=$(get "dedicated latency K=10 median end to end (1 kHz)")
fba_lat_p99=$(get "dedicated latency K=10 p99 end to end (1 kHz)")
fba_pool_lat=$(get "pooled latency K=10 median end to end (1 kHz)")
fba_build=$(get "build a task of 1000 components (CPU)")
printf '%-58s %10s ns wall %10s ns CPU\n' "fba per extra hop, deterministic (one thread):" "$fba_det" "$fba_det_cpu"
printf '%-58s %10s ns wall %10s ns CPU\n' "fba per extra hop, thread: dedicated (a thread each):" "$fba_ded" "$fba_ded_cpu"
printf '%-58s %10s ns wall %10s ns CPU\n' "fba per extra hop, pooled executor (no gst counterpart):" "$fba_pool" "$fba_pool_cpu"
printf '%-58s %10s us median %7s us p99\n' "fba latency, 10 dedicated hops, 1 kHz, end to end:" "$fba_lat" "$fba_lat_p99"
printf '%-58s %10s us median\n' "fba latency, 10 pooled hops, 1 kHz, end to end:" "$fba_pool_lat"
printf '%-58s %10s ms\n' "fba build of a 1000-component task (CPU):" "$fba_build"

echo "== one thread, whole processes in turn (gst-launch-1.0 and fba-run, least CPU of 5 rounds)"
read -r turn_gst turn_fba < <(in_turn 5 200000)
printf '%-58s %10s ns CPU\n' "gst per extra identity:" "$turn_gst"
printf '%-58s %10s ns CPU\n' "fba per extra hop, deterministic:" "$turn_fba"

echo "== ratios, fba / GStreamer (below 1: fba costs less)"
printf '%-58s %10s CPU\n' "one thread, whole processes in turn (the target's figure):" "$(ratio "$turn_fba" "$turn_gst")"
printf '%-58s %10s wall %10s CPU\n' "one thread (deterministic / identity):" "$(ratio "$fba_det" "$gst_one")" "$(ratio "$fba_det_cpu" "$gst_one_cpu")"
printf '%-58s %10s wall %10s CPU\n' "a thread per element (dedicated / queue ! identity):" "$(ratio "$fba_ded" "$gst_queue")" "$(ratio "$fba_ded_cpu" "$gst_queue_cpu")"
printf '%-58s %10s median\n' "latency, 10 threaded hops at 1 kHz (dedicated / queue):" "$(ratio "$fba_lat" "$gst_lat")"
