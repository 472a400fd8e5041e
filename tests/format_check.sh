#!/bin/bash
# Every C++ file of the project as the root .clang-format writes it.
# Usage: format_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
command -v clang-format > /dev/null || { echo "FAIL: clang-format is not installed" >&2; exit 1; }
files=$(find rig sim scenes fovea experiments tests -name '*.cc' -o -name '*.h' | sort)
bad=()
for f in $files; do
  clang-format --style=file "$f" | cmp -s - "$f" || bad+=("$f")
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "FAIL: ${#bad[@]} files differ from .clang-format (run clang-format -i on them): ${bad[*]}" >&2
  exit 1
fi
echo "PASS: $(echo "$files" | wc -l) files as .clang-format writes them"
