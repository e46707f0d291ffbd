#!/usr/bin/env bash
# The project's size rules, checked so that they stay kept (README, "Tests"):
#   - no source file over 800 lines;
#   - no C++ function over 120 lines unless its body opens with a one-line reason, a // comment
#     (universal-ctags finds the functions and their last lines; its JavaScript parser gives no
#     last line, so the page's scripts are held to the file rule only).
# usage: check_sizes.sh ROOT      check the source folders under ROOT
#        check_sizes.sh --self-test   check that a file and a function over the limits are named
set -euo pipefail

max_file_lines=800
max_function_lines=120

if ! command -v ctags >/dev/null || [[ $(ctags --version 2>/dev/null) != *"Universal Ctags"* ]]; then
  echo "check_sizes.sh: expected universal-ctags as ctags (Debian package universal-ctags), found: $(command -v ctags || echo "no ctags")" >&2
  exit 2
fi

# check ROOT: prints one line per file or function over its limit; returns 1 if any.
check() {
  local root=$1 found=0
  [ -d "$root" ] || { echo "check_sizes.sh: expected a folder, found '$root'" >&2; return 2; }
  local folders=() f
  for f in core libs plugins hardware tools tests examples cmake web/src web/tests web/scripts; do
    [ -d "$root/$f" ] && folders+=("$root/$f")
  done
  ((${#folders[@]})) || { echo "check_sizes.sh: no source folders under '$root'" >&2; return 2; }
  local sources
  sources=$(find "${folders[@]}" -name node_modules -prune -o -type f \
    \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' -o -name '*.cc' -o -name '*.js' -o -name '*.mjs' \
       -o -name '*.py' -o -name '*.sh' -o -name '*.cmake' -o -name CMakeLists.txt \) -print | sort)
  # One wc for every file (xargs may split it; each part ends with a "total" line, skipped).
  local long_files
  long_files=$(xargs -d '\n' wc -l -- <<<"$sources" |
    awk -v max="$max_file_lines" -v root="$root/" '{ n = $1; sub(/^ *[0-9]+ /, ""); if (index($0, root) == 1) $0 = substr($0, length(root) + 1) }
      $0 != "total" && n > max { print $0 ": " n " lines (a source file has at most " max ": split it by what it defines)" }')
  if [ -n "$long_files" ]; then
    echo "$long_files"
    found=1
  fi
  # Each C++ function with its first and last line; a long one passes if the line after its opening
  # brace is a comment.
  local long
  long=$({ grep -E '\.(cpp|hpp|h|cc)$' <<<"$sources" || true; } |
    ctags -L - -x --_xformat='%n	%{end}	%F	%N' --kinds-C++=f --fields=+ne --languages=C++ |
    awk -F'\t' -v max="$max_function_lines" '$2 != "" && $2 - $1 + 1 > max { print $3 "\t" $1 "\t" $2 "\t" $4 }')
  while IFS=$'\t' read -r file first last name; do
    [ -n "$file" ] || continue
    # The body's first line: the line after the first one (from the signature on) holding '{'.
    local reason
    reason=$(awk -v first="$first" -v last="$last" 'NR >= first && NR <= last {
               if (open) { print; exit } if (index($0, "{")) open = 1 }' "$file")
    if ! [[ $reason =~ ^[[:space:]]*// ]]; then
      echo "${file#"$root"/}:$first: $name is $((last - first + 1)) lines (at most $max_function_lines, or open its body with a one-line // reason)"
      found=1
    fi
  done <<<"$long"
  return $found
}

if [ "${1:-}" = "--self-test" ]; then
  dir=$(mktemp -d)
  trap 'rm -rf "$dir"' EXIT
  mkdir -p "$dir/core"
  for i in $(seq 801); do echo "// line $i"; done >"$dir/core/long_file.cpp"
  {
    echo "int long_function(int x) {"
    for i in $(seq 125); do echo "  x += $i;"; done
    echo "  return x;"
    echo "}"
    echo "int long_with_reason(int x) {"
    echo "  // One function: the steps read in order, each a line."
    for i in $(seq 125); do echo "  x -= $i;"; done
    echo "  return x;"
    echo "}"
  } >"$dir/core/functions.cpp"
  rc=0
  out=$(check "$dir") || rc=$?
  echo "$out"
  expected=("core/long_file.cpp: 801 lines" "core/functions.cpp:1: long_function is 128 lines")
  ((rc == 1)) || { echo "self-test: expected the check to fail (1), it returned $rc" >&2; exit 1; }
  for e in "${expected[@]}"; do
    grep -qF "$e" <<<"$out" || { echo "self-test: expected a line starting '$e', found none" >&2; exit 1; }
  done
  ! grep -q long_with_reason <<<"$out" || { echo "self-test: long_with_reason has its reason, yet was named" >&2; exit 1; }
  [ "$(wc -l <<<"$out")" -eq 2 ] || { echo "self-test: expected exactly two findings" >&2; exit 1; }
  echo "self-test passed"
  exit 0
fi

[ $# -eq 1 ] || { echo "usage: check_sizes.sh ROOT | --self-test" >&2; exit 2; }
check "$1"
echo "every source file within $max_file_lines lines, every C++ function within $max_function_lines or with its reason"
