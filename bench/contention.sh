#!/usr/bin/env bash
# What work on the second CPU costs the kernel on the first: the median wall time of 9 runs of
# lj_32k_shifted (100 steps, no claims, CPU 0) with CPU 1 idle, spinning in a shell loop,
# copying 4 MB arrays (cache-sized) and copying 128 MB arrays (memory-sized), then idle again.
# If the two CPUs were independent, only the copies could cost anything (shared caches and
# memory bandwidth); on a machine whose CPUs share a core or a power budget, any load does.
#
#     bash bench/contention.sh [BINARY]    (default target/release/lagra; needs .venv's numpy)
set -euo pipefail
bin=${1:-target/release/lagra}
py=.venv/bin/python
median() {
  for _ in $(seq 9); do
    taskset -c 0 "$bin" run scenes/bench/lj_32k_shifted.lagra --steps 100 --json |
      python3 -c "import json,sys; print(json.load(sys.stdin)['wall_s'])"
  done | sort -n | sed -n 5p
}
beside() { # a label, then the load's command
  local label=$1; shift
  taskset -c 1 "$@" & local load=$!
  sleep 1
  echo "$label $(median) s"
  kill "$load"; wait "$load" 2>/dev/null || true
}
echo "idle $(median) s"
beside "spinning" sh -c 'while :; do :; done'
beside "copying 4 MB" "$py" -c "import numpy as np
a = np.ones(2**19)
while True: a.copy()"
beside "copying 128 MB" "$py" -c "import numpy as np
a = np.ones(2**24)
while True: a.copy()"
echo "idle $(median) s"
