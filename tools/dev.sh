#!/usr/bin/env bash
# The two things a developer does, from a fresh Debian 12 machine:
#   tools/dev.sh run    install what is missing, build, run the main task (tasks/grasp.yaml: the grasp loop in simulation)
#   tools/dev.sh test   install what is missing, build and run every test: plain (with the live
#                       view's page in headless Chromium), under AddressSanitizer +
#                       UndefinedBehaviorSanitizer, the runtime's concurrency tests under
#                       ThreadSanitizer, and the task-loader fuzzer
# Builds go to build/<config>; FBA_JOBS sets the parallelism (default: all cores). With ccache
# installed every build goes through it, so a second run recompiles only what changed.
# FBA_FUZZ_RUNS (default 18000) bounds the fuzzer's exploration, in inputs run.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$PWD
jobs=${FBA_JOBS:-$(nproc)}

packages=(
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  libyaml-cpp-dev libboost-dev libboost-program-options-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libeigen3-dev libopencv-dev libassimp-dev libqhull-dev libmujoco-dev
  liburdfdom-dev libkdl-parser-dev liborocos-kdl-dev libmodbus-dev libompl-dev libfcl-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gstreamer1.0-tools gstreamer1.0-plugins-base graphviz bc ccache
  universal-ctags  # the size rules' check (tests/source_sizes)
  chromium  # the live view's browser tests (web/tests/, driven by playwright-core from npm)
)
# The live view's page (web/) is built with npm and vite: Debian's nodejs and npm, unless a Node.js
# with npm is there already (NodeSource's nodejs carries its own npm, with which Debian's npm package
# conflicts). The build installs the page's npm packages itself (npm ci, once per package-lock.json).
command -v npm >/dev/null || packages+=(nodejs npm)

install_packages() {
  local missing=()
  for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "== installing: ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -eq 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
}

# Decided after install_packages, which installs ccache on a fresh machine: decided before, the
# first run (CI's, on a new machine) compiled without it and left the cache empty for the next.
use_ccache() {
  launcher=()
  command -v ccache >/dev/null || return 0
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  # Paths relative to the checkout, and the build folder left out of the hash, which ccache puts in
  # it whenever there is debug info (every build here has line tables): so a clone in another folder,
  # as CI's is, hits the entries this one made. The price: an object's debug info may name the folder
  # of the clone that compiled it first. CCACHE_NOHASHDIR=false restores the default.
  export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$top}
  export CCACHE_NOHASHDIR=${CCACHE_NOHASHDIR:-true}
}

# configure <name> [cmake args...]
# Each test binary is one CTest test (FBA_TEST_EACH_CASE=OFF, cmake/FbaTests.cmake): a process per
# case spent more time loading OpenCV's 150 shared libraries than testing.
# A unity build (CMAKE_UNITY_BUILD): each target's sources compile in batches of eight as one file,
# so the headers (Eigen, OpenCV, nlohmann/json, spdlog, GoogleTest) are parsed and their templates
# compiled once a batch, not once a file: a third less compile time with nothing cached. The price
# is paid when iterating: an edit recompiles its whole batch. For a quicker edit-build loop,
# configure a build of your own with -DCMAKE_UNITY_BUILD=OFF. (The figures behind each build choice
# here are in docs/results.md, "CI time".)
configure() {
  local name=$1
  shift
  cmake -S "$top" -B "build/$name" -G Ninja "${launcher[@]}" -DFBA_TEST_EACH_CASE=OFF -DCMAKE_UNITY_BUILD=ON "$@" \
    >"build/$name.configure.log" 2>&1 ||
    { cat "build/$name.configure.log"; exit 1; }
}

# stage <title>: prints the title, and the previous stage's wall time, so CI logs show where time goes.
stage_start=$SECONDS
stage_name=""
stage() {
  [ -z "$stage_name" ] || echo "== $stage_name: $((SECONDS - stage_start)) s"
  stage_name=$1
  stage_start=$SECONDS
  [ -z "$1" ] || echo "== $1"
}

# The sanitizer builds: -O0 -g1, and -O2 for the targets that compute (FBA_COMPUTE_FLAGS, marked by
# fba_compute_target: their tests need optimised code to run in minutes); line tables are all a
# sanitizer report needs. Optimising is most of an instrumented build's compile time, which is most
# of a CI run on a cold cache; the tests of the code that computes would crawl unoptimised.
# They are compiled by clang, the sanitizers' home, which instruments faster than GCC.
# The plain build stays with the system's compiler (GCC on Debian), so CI compiles with both.
sanitized=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++
  -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O0 -g1 -DNDEBUG" -DFBA_COMPUTE_FLAGS=-O2)
# The plain build: optimised as a user runs it, with line tables (-g1: backtraces, perf and crash
# reports name file and line) rather than full debug info, which costs a third more compile time.
# Configure your own build for gdb.
plain=(-DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -g1 -DNDEBUG")

build() { cmake --build "build/$1" --parallel "$jobs" "${@:2}"; }

# behind <log> <command...>: runs the next stage's work (a sanitizer build, the fuzzer) while this
# stage's build and tests run, at the lowest priority, so that it takes mostly what they leave idle
# (a target waiting on the one it links, the hardware tests waiting on timeouts, the last binary
# running alone). Its output goes to <log>, which wait_behind prints. It runs in a session of its
# own, so that a failing stage stops it and its children. A new session is a new scheduling group
# where the kernel groups by session (sched_autogroup, on in Debian's kernels), and a nice value
# ranks a process only within its group: so the group is niced too (/proc/self/autogroup), or the
# work behind takes half the cores from the tests whatever its nice value (docs/results.md, "CI time").
behind_pid=""
behind() {
  local log=$1
  shift
  setsid -w bash -c 'echo 19 >/proc/self/autogroup 2>/dev/null || true; exec nice -n 19 "$@"' behind "$@" >"$log" 2>&1 &
  behind_pid=$!
}
trap '[ -z "$behind_pid" ] || kill -- "-$behind_pid" 2>/dev/null || true' EXIT
# wait_behind <log>: waits for it, prints its output and returns its exit status.
wait_behind() {
  local rc=0
  wait "$behind_pid" || rc=$?
  behind_pid=""
  cat "$1"
  return "$rc"
}
build_behind() { behind "build/$1.build.log" cmake --build "build/$1" --parallel "$jobs" "${@:2}"; }
wait_build() { wait_behind "build/$1.build.log" || { echo "== the $1 build failed (above)"; exit 1; }; }

# A failing case's output scrolls away among the others' lines; on failure it is printed again at the
# end, where a CI log's tail shows it: from each failed binary, the output of each failed case (from
# its "[ RUN" line to its "[  FAILED" line) and of a case that never finished (a crash, a timeout).
run_tests() {
  local name=$1
  shift
  (cd "build/$name" && ctest --output-on-failure --parallel "$jobs" --timeout 900 "$@") && return 0
  local rc=$?
  echo "== failed in build/$name, their failed cases again:"
  awk -F: 'NR == FNR { failed[$2] = 1; next }
           function flush() { if (show && running) printf "%s", buf; buf = ""; running = 0 }
           /^[0-9]+\/[0-9]+ Testing: / { flush(); name = $0; sub(/^[0-9]+\/[0-9]+ Testing: /, "", name)
                                          show = name in failed; if (show) print "== " name; next }
           !show { next }
           /^\[ RUN      \]/ { buf = ""; running = 1 }
           running { buf = buf $0 "\n" }
           /^\[       OK \]/ { buf = ""; running = 0 }
           /^\[  FAILED  \] .*\(/ { printf "%s", buf; buf = ""; running = 0 }
           /^Test (Passed|Failed)|^<end of output>/ { flush() }
           END { flush() }' \
    "build/$name/Testing/Temporary/LastTestsFailed.log" "build/$name/Testing/Temporary/LastTest.log" | tail -c 40000
  exit "$rc"
}

cmd=${1:-}
mkdir -p build
case "$cmd" in
  run)
    install_packages
    use_ccache
    configure release "${plain[@]}"  # the same build as 'test' uses
    build release --target fba_programs
    task=${2:-tasks/grasp.yaml}
    echo "== build/release/bin/fba-run $task --output-dir out/$(basename "$task" .yaml)"
    build/release/bin/fba-run "$task" --output-dir "out/$(basename "$task" .yaml)"
    ;;
  test)
    install_packages
    use_ccache
    # The ASan build starts behind the plain build (build_behind), the TSan build behind the ASan
    # tests and the fuzzer behind the TSan tests, so a stage's time in the log holds the rest of its
    # own work and its tests; the fuzzing stage is what its exploration outlasts them by.
    stage "plain build and tests"
    configure release "${plain[@]}"
    # The sanitizer builds compile only what their tests run (fba_tests: every test target, cmake/FbaTests.cmake,
    # with fba-run, fba-evaluate and the plugins as dependencies). Their vision tests carve smaller
    # problems than the plain build's (FBA_TEST_SANITIZED), which keeps the full-size targets.
    # The task loader's fuzzer is built here too; its seeds replay among the tests (label fuzz).
    configure asan "${sanitized[@]}" -DFBA_SANITIZE=address,undefined -DFBA_BUILD_FUZZERS=ON -DFBA_BUILD_BENCHMARKS=OFF
    build_behind asan --target fba_tests
    build release
    run_tests release
    # The runtime's hop and loader against plain code in the same run, and those ratios against the
    # committed ones: a change that makes them slower is named here, the day it lands (not failed:
    # figures on a shared machine are for a person to read).
    echo "== runtime benchmark against tools/runtime-benchmark/reference.json"
    build/release/bin/fba-runtime-benchmark --quick --reference tools/runtime-benchmark/reference.json |
      grep -E '^(ratio|REGRESSION|as before|no regression)'

    stage "AddressSanitizer + UndefinedBehaviorSanitizer"
    wait_build asan
    # The grasp library's parallel loops on the task's pool too (fba_grasp_threads_tests): it needs
    # the vision libraries configured, though only these targets and what they link are built.
    configure tsan "${sanitized[@]}" -DFBA_SANITIZE=thread -DFBA_BUILD_BENCHMARKS=OFF
    tsan_tests=(fba_core_tests fba_task_tests fba_inspect_tests fba_can_tests fba_canopen_tests fba_canopen_program_tests
      fba_canopen_arm_tests fba_robotiq_3f_tests fba_robotiq_3f_program_tests fba_grasp_threads_tests fba_serve_tests
      fba_run_views_tests)
    build_behind tsan --target "${tsan_tests[@]}"
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      LSAN_OPTIONS=suppressions=$top/tests/lsan.supp \
      run_tests asan -LE "install|benchmark"

    stage "ThreadSanitizer: the runtime's concurrency tests, the hardware drivers' threads, grasp's parallel loops"
    wait_build tsan
    # The fuzzer explores behind these tests: a bound in inputs run, not seconds, so that its share
    # of the cores does not change how much it explores.
    [ -z "${FBA_FUZZ_SECONDS:-}" ] ||
      echo "== warning: FBA_FUZZ_SECONDS=$FBA_FUZZ_SECONDS is no longer read; the bound is FBA_FUZZ_RUNS, inputs (default 18000)"
    behind build/asan/fuzz.log bash tests/fuzz/run.sh build/asan 600 "${FBA_FUZZ_RUNS:-18000}"
    # In-process tests only: the command-line tests (Cli*, and the random signals' binary) run fba-run
    # as a process and check its crash and signal handling, which by design calls what TSan calls
    # signal-unsafe (the best-effort crash report); they run in the plain and ASan stages.
    GTEST_FILTER='-Cli*' TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 \
      run_tests tsan -R "^($(IFS='|'; echo "${tsan_tests[*]}"))\$"

    stage "fuzzing the task loader: a bounded exploration (the ASan build's fuzzer)"
    # Exploration finds new inputs only now and then, so it cannot decide whether CI passes (that
    # would make CI a coin toss): run.sh saves a finding into tests/fuzz/corpus/ and this prints it,
    # whole, so that it can be committed with its fix; the replay above then keeps it fixed.
    fuzz_rc=0
    wait_behind build/asan/fuzz.log || fuzz_rc=$?
    ((fuzz_rc != 2)) || { echo "== tests/fuzz/run.sh could not start (above)"; exit 2; }  # its usage errors
    # The live view's request handling, after it: a request parses in microseconds, so a short
    # exploration of its own, bounded in inputs too (FBA_FUZZ_REQUEST_RUNS).
    echo "== fuzzing the live view's request handling"
    request_rc=0
    bash tests/fuzz/run.sh build/asan 300 "${FBA_FUZZ_REQUEST_RUNS:-100000}" request_handling >build/asan/fuzz-request.log 2>&1 ||
      request_rc=$?
    ((request_rc != 2)) || { cat build/asan/fuzz-request.log; echo "== tests/fuzz/run.sh could not start (above)"; exit 2; }
    grep -E '^(stat::number_of_executed_units|Done|==[0-9]+==)' build/asan/fuzz-request.log || true
    if ((fuzz_rc || request_rc)); then
      for f in build/asan/fuzz-findings/* build/asan/fuzz-findings-request_handling/*; do
        [ -f "$f" ] || continue
        corpus=corpus
        [[ $f != */fuzz-findings-request_handling/* ]] || corpus=corpus_request_handling
        echo "== NEW FUZZ FINDING (commit it as tests/fuzz/$corpus/finding-$(basename "$f") with its fix), base64:"
        base64 -w 0 "$f"
        echo
      done
    fi
    stage ""
    echo "== all tests passed in $SECONDS s"
    ;;
  *)
    echo "usage: tools/dev.sh run [TASK.yaml] | test" >&2
    exit 2
    ;;
esac
