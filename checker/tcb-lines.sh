#!/usr/bin/env bash
# Lines of code in the checker's trusted core: checker/src, without comments, blank lines and
# the test modules (every file keeps its tests at the end, after `#[cfg(test)]`).
cd "$(dirname "$0")/src" || exit 2
total=0
for f in $(find . -name '*.rs' | sort); do
  n=$(awk '/^#\[cfg\(test\)\]/ { exit } !/^[[:space:]]*(\/\/|$)/ { n++ } END { print n + 0 }' "$f")
  [ "${1:-}" = "-v" ] && printf '%5d  checker/src/%s\n' "$n" "${f#./}"
  total=$((total + n))
done
echo "$total"
