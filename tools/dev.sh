#!/usr/bin/env bash
# The two things a developer does, from a fresh Debian 12 machine:
#   tools/dev.sh run    install what is missing, build, run the main task
#   tools/dev.sh test   install what is missing, build and run every test: plain, under
#                       AddressSanitizer + UndefinedBehaviorSanitizer, the runtime's
#                       concurrency tests under ThreadSanitizer, and the task-loader fuzzer
# Builds go to build/<config>; FBA_JOBS sets the parallelism (default: all cores).
set -euo pipefail
cd "$(dirname "$0")/.."
top=$PWD
jobs=${FBA_JOBS:-$(nproc)}

packages=(
  build-essential cmake ninja-build pkg-config clang libclang-rt-14-dev
  libyaml-cpp-dev libboost-program-options-dev libspdlog-dev libfmt-dev nlohmann-json3-dev
  libeigen3-dev libopencv-dev libassimp-dev libqhull-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  gstreamer1.0-tools gstreamer1.0-plugins-base graphviz bc
)

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

# configure <name> [cmake args...]
configure() {
  local name=$1
  shift
  cmake -S "$top" -B "build/$name" -G Ninja "$@" >"build/$name.configure.log" 2>&1 ||
    { cat "build/$name.configure.log"; exit 1; }
}

build() { cmake --build "build/$1" --parallel "$jobs" "${@:2}"; }

run_tests() {
  local name=$1
  shift
  (cd "build/$name" && ctest --output-on-failure --parallel "$jobs" --timeout 900 "$@")
}

cmd=${1:-}
mkdir -p build
case "$cmd" in
  run)
    install_packages
    configure release -DCMAKE_BUILD_TYPE=RelWithDebInfo  # the same build as 'test' uses
    build release --target fba_programs
    task=${2:-tasks/carve_dino.yaml}
    [ -f "$task" ] || task=tasks/examples/chain.yaml
    echo "== build/release/bin/fba-run $task --output-dir out/$(basename "$task" .yaml)"
    build/release/bin/fba-run "$task" --output-dir "out/$(basename "$task" .yaml)"
    ;;
  test)
    install_packages
    echo "== plain build and tests"
    configure release -DCMAKE_BUILD_TYPE=RelWithDebInfo
    build release
    run_tests release

    echo "== AddressSanitizer + UndefinedBehaviorSanitizer"
    # -O2 with sanitizers: the vision tests carve real data, which -O0 would make slow.
    configure asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFBA_SANITIZE=address,undefined -DFBA_BUILD_BENCHMARKS=OFF
    build asan
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      LSAN_OPTIONS=suppressions=$top/tests/lsan.supp \
      run_tests asan -LE "install|benchmark"

    echo "== ThreadSanitizer: the runtime's concurrency tests"
    configure tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFBA_SANITIZE=thread -DFBA_BUILD_VISION=OFF -DFBA_BUILD_BENCHMARKS=OFF
    build tsan --target fba_core_tests fba_task_tests
    TSAN_OPTIONS=halt_on_error=1:second_deadlock_stack=1 run_tests tsan -L "core|tasks"

    if [ -f tests/fuzz/run.sh ]; then
      echo "== fuzzing the task loader"
      CC=clang CXX=clang++ configure fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFBA_BUILD_FUZZERS=ON -DFBA_BUILD_VISION=OFF \
        -DFBA_SANITIZE=fuzzer-no-link,address,undefined \
        -DFBA_BUILD_BENCHMARKS=OFF
      build fuzz --target fuzz_task_loader
      bash tests/fuzz/run.sh build/fuzz "${FBA_FUZZ_SECONDS:-60}"
    fi
    ;;
  *)
    echo "usage: tools/dev.sh run [TASK.yaml] | test" >&2
    exit 2
    ;;
esac
