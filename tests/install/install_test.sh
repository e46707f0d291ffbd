#!/usr/bin/env bash
# Installs fba into <work>/prefix, builds the out-of-tree example plugin against that prefix
# only, and runs it with the installed fba-run and fba-inspect. Every step names what failed;
# its full output is in a log under <work>. Usage (ctest passes all of these):
#   install_test.sh --build DIR --example DIR --work DIR [--libdir lib] [--cmake cmake]
#                   [--generator Ninja] [--cxx c++] [--web-page ON|OFF]
# --web-page ON: the build made the live view's page (FBA_BUILD_WEB), which must then be installed
# in share/fba/web with every file of it, and found there by the installed fba-run.
set -uo pipefail

build="" example="" work="" libdir=lib cmake=cmake generator=Ninja cxx=c++ web_page=OFF
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build=$2 ;;
    --example) example=$2 ;;
    --work) work=$2 ;;
    --libdir) libdir=$2 ;;
    --cmake) cmake=$2 ;;
    --generator) generator=$2 ;;
    --cxx) cxx=$2 ;;
    --web-page) web_page=$2 ;;
    *) echo "install_test: unknown argument '$1'" >&2; exit 2 ;;
  esac
  shift 2
done
if [ -z "$build" ] || [ -z "$example" ] || [ -z "$work" ]; then
  echo "usage: install_test.sh --build DIR --example DIR --work DIR [--libdir lib] [--cmake cmake] [--generator G] [--cxx c++] [--web-page ON|OFF]" >&2
  exit 2
fi

step_no=0
step() { step_no=$((step_no + 1)); current="$*"; echo "[$step_no] $*"; }
fail() {
  echo "install_test: FAILED at step $step_no ($current): $1" >&2
  if [ $# -gt 1 ] && [ -f "$2" ]; then
    echo "---- last lines of $2 ----" >&2
    tail -n 40 "$2" >&2
  fi
  exit 1
}
# run LOG CMD...: runs a command with its output in LOG; returns its exit status.
run() { local log=$1; shift; echo "    \$ $*" >>"$work/commands.txt"; "$@" >"$log" 2>&1; }

# Nothing from the environment may help: the installed programs must find their libraries
# through their RPATHs, their plugins and their page beside themselves.
unset FBA_PLUGIN_PATH LD_LIBRARY_PATH FBA_WEB_DIR

rm -rf "$work" || { echo "install_test: cannot remove $work" >&2; exit 1; }
mkdir -p "$work" || { echo "install_test: cannot create $work" >&2; exit 1; }
prefix=$work/prefix
oot=$work/oot-build

# (a) ------------------------------------------------------------------------------------------
step "cmake --install $build --prefix $prefix"
run "$work/install.log" "$cmake" --install "$build" --prefix "$prefix" ||
  fail "cmake --install failed; every installed target must be built first (ninja -C $build fba_programs)" "$work/install.log"
prefix=$(cd "$prefix" && pwd -P)  # /proc/self/exe reports the real path

step "install layout: programs, plugins, headers, CMake package"
for f in bin/fba-run bin/fba-inspect bin/fba-plugin-manifest \
         "$libdir/libfba.so" "$libdir/fba/plugins/fba-examples.so" "$libdir/fba/plugins/fba-examples.manifest.json" \
         "$libdir/fba/plugins/relay.yaml" \
         include/fba/component.hpp include/fba/spec.hpp include/fba/plugin.hpp include/fba/testing.hpp \
         include/fba/registry.hpp include/fba/version.hpp \
         "$libdir/cmake/fba/fbaConfig.cmake" "$libdir/cmake/fba/fbaConfigVersion.cmake" \
         "$libdir/cmake/fba/fbaTargets.cmake" "$libdir/cmake/fba/FbaPlugin.cmake"; do
  [ -e "$prefix/$f" ] || fail "missing from the install tree: $prefix/$f (see $work/install.log)"
done
[ -x "$prefix/bin/fba-run" ] && [ -x "$prefix/bin/fba-inspect" ] || fail "bin/fba-run or bin/fba-inspect is not executable"
grep -q '#define FBA_VERSION "[0-9]' "$prefix/include/fba/version.hpp" ||
  fail "include/fba/version.hpp is not the generated header (no FBA_VERSION)"
if command -v readelf >/dev/null; then
  while IFS= read -r elf; do
    if readelf -d "$elf" 2>/dev/null | grep -E 'R(UN)?PATH' | grep -qF "$build"; then
      fail "$elf keeps an RPATH into the build tree: $(readelf -d "$elf" | grep -E 'R(UN)?PATH')"
    fi
  done < <(find "$prefix/bin" "$prefix/$libdir" -type f \( -name '*.so*' -o -perm -u+x \) 2>/dev/null)
  readelf -d "$prefix/$libdir/fba/plugins/fba-examples.so" | grep -qF '$ORIGIN/../..' ||
    fail "the installed example plugin has no RPATH \$ORIGIN/../.. to find libfba"
fi

if [ "$web_page" = ON ]; then
  step "install layout: the live view's page in share/fba/web, every file of it"
  built_web=$build/share/fba/web
  web=$prefix/share/fba/web
  [ -f "$built_web/index.html" ] || fail "the build made no page ($built_web/index.html): build fba_programs first"
  for f in index.html report.html; do
    [ -s "$web/$f" ] || fail "missing or empty in the install tree: $web/$f (see $work/install.log)"
  done
  # The same files as the build's page, byte for byte: a page missing its scripts or styles loads blank.
  while IFS= read -r f; do
    cmp -s "$built_web/$f" "$web/$f" || fail "share/fba/web/$f is not installed as built ($built_web/$f)"
  done < <(cd "$built_web" && find . -type f | sed 's|^\./||')
  # What the index loads (./assets/...) is there.
  assets=$(grep -oE '(src|href)="\./assets/[^"]+"' "$web/index.html" | sed -E 's/^(src|href)="\.\///; s/"$//')
  [ -n "$assets" ] || fail "$web/index.html loads no ./assets/ file: not the page vite builds"
  for a in $assets; do
    [ -s "$web/$a" ] || fail "$web/index.html loads $a, which is not installed"
  done
  grep -qF '<!--FBA_REPORT_DATA-->' "$web/report.html" || fail "$web/report.html has no <!--FBA_REPORT_DATA--> marker: not the report template"
fi

# (b) ------------------------------------------------------------------------------------------
step "configure examples/out-of-tree-plugin with -DCMAKE_PREFIX_PATH=$prefix"
run "$work/oot-configure.log" "$cmake" -S "$example" -B "$oot" -G "$generator" -DCMAKE_CXX_COMPILER="$cxx" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF ||
  fail "the out-of-tree example does not configure against the installed package" "$work/oot-configure.log"
found=$(sed -n 's/^fba_DIR:PATH=//p' "$oot/CMakeCache.txt")
[ "$(cd "$found" 2>/dev/null && pwd -P)" = "$prefix/$libdir/cmake/fba" ] ||
  fail "find_package(fba) found '$found', not the package installed in $prefix/$libdir/cmake/fba"

step "build examples/out-of-tree-plugin"
run "$work/oot-build.log" "$cmake" --build "$oot" --parallel 2 ||
  fail "the out-of-tree example does not build against the installed package" "$work/oot-build.log"
[ -f "$oot/fba-demo.so" ] || fail "the build made no $oot/fba-demo.so"
[ -f "$oot/fba-demo.manifest.json" ] || fail "the build wrote no manifest $oot/fba-demo.manifest.json (fba::plugin-manifest)" "$work/oot-build.log"
[ -x "$oot/scale_test" ] || fail "the build made no $oot/scale_test (was GTest found?)" "$work/oot-configure.log"

# (c) ------------------------------------------------------------------------------------------
step "$prefix/bin/fba-inspect (no flags) lists the installed plugins"
run "$work/inspect-all.log" "$prefix/bin/fba-inspect" ||
  fail "the installed fba-inspect exits with an error" "$work/inspect-all.log"
grep -qF "$prefix/$libdir/fba/plugins/fba-examples.so" "$work/inspect-all.log" ||
  fail "the installed fba-inspect does not load its own plugin $prefix/$libdir/fba/plugins/fba-examples.so" "$work/inspect-all.log"
for t in examples.counter examples.sink examples.relay; do
  grep -qF "$t" "$work/inspect-all.log" || fail "the installed fba-inspect does not list $t" "$work/inspect-all.log"
done
if grep -qF "$build/$libdir/fba/plugins" "$work/inspect-all.log"; then
  fail "the installed fba-inspect looks into the build tree's plugins" "$work/inspect-all.log"
fi

step "fba-inspect shows data types, --version, and refuses a plugin folder that does not exist"
grep -qF "fba.Int  (size 8, alignment 8, version 1, <fba/packet.hpp>)" "$work/inspect-all.log" ||
  fail "the installed fba-inspect does not list the data type fba.Int with its layout" "$work/inspect-all.log"
run "$work/inspect-int.log" "$prefix/bin/fba-inspect" fba.Int || fail "fba-inspect fba.Int failed" "$work/inspect-int.log"
grep -qF "layout: size 8, alignment 8, version 1" "$work/inspect-int.log" ||
  fail "fba-inspect fba.Int does not show its layout" "$work/inspect-int.log"
run "$work/inspect-version.log" "$prefix/bin/fba-inspect" --version || fail "fba-inspect --version failed" "$work/inspect-version.log"
grep -q '^fba-inspect [0-9]' "$work/inspect-version.log" || fail "fba-inspect --version prints no version" "$work/inspect-version.log"
run "$work/inspect-nonexistent.log" "$prefix/bin/fba-inspect" -p "$work/no-such-folder"
status=$?
[ $status -eq 2 ] || fail "fba-inspect -p <missing folder>: expected exit 2, got $status" "$work/inspect-nonexistent.log"
grep -qF "is not a folder" "$work/inspect-nonexistent.log" || fail "fba-inspect -p <missing folder> does not say so" "$work/inspect-nonexistent.log"

# (d) ------------------------------------------------------------------------------------------
step "fba-inspect --plugin-path $oot demo.scale"
run "$work/inspect-scale.log" "$prefix/bin/fba-inspect" --plugin-path "$oot" demo.scale ||
  fail "fba-inspect cannot show demo.scale from the out-of-tree build" "$work/inspect-scale.log"
for s in "demo.scale (filter)" "factor  int, default 2, range [-1000, 1000]" "overflow"; do
  grep -qF "$s" "$work/inspect-scale.log" || fail "fba-inspect demo.scale does not show '$s'" "$work/inspect-scale.log"
done

# (e) ------------------------------------------------------------------------------------------
step "fba-run without the plugin path refuses demo.scale (exit 2)"
run "$work/run-no-path.log" "$prefix/bin/fba-run" "$example/scale.yaml"
status=$?
[ $status -eq 2 ] || fail "expected exit 2 (configuration error) without the plugin, got $status" "$work/run-no-path.log"
grep -qF "unknown component type 'demo.scale'" "$work/run-no-path.log" ||
  fail "the error does not name the unknown type demo.scale" "$work/run-no-path.log"

step "fba-run --plugin-path $oot scale.yaml"
run "$work/run-flag.log" "$prefix/bin/fba-run" --timeout 120 --plugin-path "$oot" --output-dir "$work/run-flag" \
  "$example/scale.yaml" || fail "fba-run --plugin-path exited with $? (0 expected)" "$work/run-flag.log"
grep -q '"outcome": "success"' "$work/run-flag/summary.json" || fail "summary.json does not say success" "$work/run-flag/summary.json"
grep -q '"name": "done"' "$work/run-flag/summary.json" || fail "the sink did not report 'done'" "$work/run-flag/summary.json"
if [ "$web_page" = ON ]; then
  # The installed fba-run found its installed page (bin/../share/fba/web): the report is filled in.
  [ -s "$work/run-flag/report.html" ] || fail "the installed fba-run wrote no report.html: it did not find $prefix/share/fba/web" "$work/run-flag.log"
  grep -qF 'id="fba-report"' "$work/run-flag/report.html" || fail "$work/run-flag/report.html holds no run data" "$work/run-flag.log"
fi

# (f) ------------------------------------------------------------------------------------------
step "FBA_PLUGIN_PATH=$oot fba-run scale.yaml"
FBA_PLUGIN_PATH="$oot" run "$work/run-env.log" "$prefix/bin/fba-run" --timeout 120 "$example/scale.yaml" ||
  fail "fba-run with FBA_PLUGIN_PATH exited with $? (0 expected)" "$work/run-env.log"

# (g) ------------------------------------------------------------------------------------------
step "the out-of-tree unit test ($oot/scale_test)"
run "$work/scale-test.log" "$oot/scale_test" || fail "scale_test failed" "$work/scale-test.log"

# An out-of-tree plugin installed into the same prefix lands where fba-run looks by itself.
step "cmake --install the out-of-tree plugin into $prefix; fba-run finds it without flags"
run "$work/oot-install.log" "$cmake" --install "$oot" --prefix "$prefix" ||
  fail "cmake --install of the out-of-tree build failed" "$work/oot-install.log"
[ -f "$prefix/$libdir/fba/plugins/fba-demo.so" ] || fail "fba-demo.so was not installed to $prefix/$libdir/fba/plugins" "$work/oot-install.log"
[ -f "$prefix/$libdir/fba/plugins/fba-demo.manifest.json" ] ||
  fail "fba-demo.manifest.json was not installed beside fba-demo.so" "$work/oot-install.log"
run "$work/run-installed.log" "$prefix/bin/fba-run" --timeout 120 "$example/scale.yaml" ||
  fail "fba-run does not find the installed demo plugin (exit $?)" "$work/run-installed.log"

echo "install_test: all $step_no steps passed (logs in $work)"
