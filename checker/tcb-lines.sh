#!/usr/bin/env bash
# Lines of code in the checker's trusted computing base, without comments, blank lines and the
# code compiled only for verification (items under #[cfg(test)], #[cfg(kani ...)] and the like).
# Prints the core (everything but the term definitions), the term definitions, and the total;
# -v lists every file.
cd "$(dirname "$0")/src" || exit 2
count() {
  awk '
    /^#!\[cfg\(test\)\]/ { n = 0; exit }
    skip == 0 && /^[[:space:]]*#\[cfg\((any\()?(test|kani)/ { skip = 1; depth = 0; opened = 0; next }
    skip == 1 {
      n_open = gsub(/\{/, "{"); n_close = gsub(/\}/, "}")
      depth += n_open - n_close; if (n_open > 0) opened = 1
      if ((opened && depth <= 0) || (!opened && /;[[:space:]]*$/)) skip = 0
      next
    }
    !/^[[:space:]]*(\/\/|$)/ { n++ }
    END { print n + 0 }' "$1"
}
core=0; terms=0
# (a test module in a file of its own, `#[cfg(test)] mod tests;` beside its code, is tests.rs)
for f in $(find . -name '*.rs' ! -name tests.rs | sort); do
  n=$(count "$f")
  [ "${1:-}" = "-v" ] && printf '%5d  checker/src/%s\n' "$n" "${f#./}"
  case "$f" in ./terms/mod.rs) core=$((core + n)) ;; ./terms/*) terms=$((terms + n)) ;; *) core=$((core + n)) ;; esac
done
echo "core $core"
echo "term definitions $terms"
echo "total $((core + terms))"
