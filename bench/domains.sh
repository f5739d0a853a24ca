#!/usr/bin/env bash
# Strong scaling of in.lj across processes on this machine, Lagra beside LAMMPS, interleaved
# rounds, the fastest of each kept. Lagra: one process on one thread, one process on two
# threads, and `mpirun -np 2` (a thread a rank, the scene cut into domains); LAMMPS -sf opt on
# one and two MPI ranks. Needs a lagra built with --features mpi (after `bash setup.sh --mpi`)
# and LAMMPS (`bash ../shared/peers/lammps.sh install`).
#
#     bash bench/domains.sh CELLS STEPS ROUNDS    # 20 100 5: 32,000 atoms; 40 100 3: 256,000
#     bash bench/domains.sh CELLS STEPS ROUNDS nvt  # in a Nose-Hoover chain (Lagra alone): the
#                                                  # thermostat's sums and the samples' cost
#
# Prints seconds per configuration (Lagra's `wall_s`, rank 0's run loop, the first list build
# and forces included; LAMMPS's loop time), and rank 0's time in exchanges from --explain.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cells=$1 steps=$2 rounds=$3 ensemble=${4:-nve}
lagra=$root/target/release/lagra
peers=${LAGRA_PEERS:-$root/../shared/peers}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$peers"/*.lmp "$work"/
sed "s/cells: \[20, 20, 20\]/cells: [$cells, $cells, $cells]/" "$root/scenes/bench/lj_32k.lagra" > "$work/lj.lagra"
if [ "$ensemble" = nvt ]; then
  sed -i 's/^  solver {/  thermostat nose_hoover { T: 1.44, tau: 0.5 }\n  solver {/' "$work/lj.lagra"
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
wall() { python3 -c "import json, sys; print(json.load(sys.stdin)['wall_s'])"; }
talk() { python3 -c "
import json, re, sys
plan = str(json.load(sys.stdin)['plan'])
m = re.search(r'spent ([0-9.]+) s of ([0-9.]+) s in exchanges', plan)
print(m.group(1) if m else '-')"; }
for _ in $(seq "$rounds"); do
  echo "lagra_1_thread $(taskset -c 0 "$lagra" run "$work/lj.lagra" --steps "$steps" --threads 1 --quiet --json | wall) -"
  echo "lagra_2_threads $(taskset -c 0,1 "$lagra" run "$work/lj.lagra" --steps "$steps" --threads 2 --quiet --json | wall) -"
  r=$(mpirun -np 2 --bind-to core "$lagra" run "$work/lj.lagra" --steps "$steps" --threads 1 --quiet --json --explain)
  echo "lagra_2_ranks $(wall <<< "$r") $(talk <<< "$r")"
  [ "$ensemble" = nvt ] && continue
  (cd "$work" && taskset -c 0 lmp -in w1.lmp -var n "$cells" -var nsteps "$steps" -sf opt -log one.log -screen none)
  echo "lammps_opt_1_rank $(awk '/Loop time of/ {print $4}' "$work/one.log") -"
  (cd "$work" && mpirun -np 2 --bind-to core lmp -in w1.lmp -var n "$cells" -var nsteps "$steps" -sf opt -log two.log -screen none > /dev/null)
  echo "lammps_opt_2_ranks $(awk '/Loop time of/ {print $4}' "$work/two.log") $(awk '/^Comm / {print $5}' "$work/two.log")"
done | awk '{ if (!($1 in m) || $2 < m[$1]) { m[$1] = $2; c[$1] = $3 } }
  END { for (k in m) printf "%-20s fastest %.3f s  (communication %s s)\n", k, m[k], c[k] }' | sort
