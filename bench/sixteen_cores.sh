#!/usr/bin/env bash
# Every goal that needs a 16-core machine (issues 39, 41 and 42), measured in one prepared call of
# about five minutes, so that a session lent a measuring machine spends its device time on the
# figures and leaves time to run it again.
#
#   bash bench/sixteen_cores.sh prepare   # here, after `cargo build --release`: the peers' kit
#                                         # (../shared/peers/device-kit.sh) and a lagra built with
#                                         # --features mpi against the kit's MPICH, into .devkit/
#   bash bench/sixteen_cores.sh           # there (the tool library's `run`, carry [".devkit"]):
#                                         # prints each figure, and writes $OUT/sixteen.txt
#   QUICK=1 bash bench/sixteen_cores.sh   # here, to try the whole script small: 32,000 atoms,
#                                         # at most two CPUs
#
# The MPICH build has its own target directory (/tmp/target-mpich, seeded from target/release:
# a few minutes warm) and finds libmpi.so.12 where the kit is unpacked there (/tmp/kit/mp/lib,
# on LD_LIBRARY_PATH). Each measurement has a time limit, so a hung rank costs two minutes, not the
# call. What it prints, in order: in.lj at 256,000 atoms on 1-16 threads beside LAMMPS-opt on
# 1-16 MPI ranks, 1,024,000 atoms on 16 of each (issue 39's scaling and LAMMPS goals); Lagra on
# 1-16 MPI ranks, and 1,024,000 atoms on 16 (issue 41); the checker's cost at 16 threads on
# 256,000 atoms and on one and two CPUs at 32,000 (39); the small scenes checked every step on one
# CPU and on all (39); `lagra bench gradient` at 1 and 16 threads (39); stack_1000 on 1, 2 and 16
# threads and two one-thread copies at once, the machine's own ceiling for two (42).
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"

if [ "${1:-}" = prepare ]; then
  set -e
  bash ../shared/peers/device-kit.sh
  rm -rf /tmp/kit && mkdir -p /tmp/kit && tar -xJf .devkit/kit.tar.xz -C /tmp/kit
  wheel=$(mktemp -d)
  python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 -d "$wheel" mpich==5.0.2
  unzip -q -o "$wheel"/mpich-*.whl 'mpich-5.0.2.data/data/include/*' -d "$wheel"
  mkdir -p /tmp/kit/mp/include && cp "$wheel"/mpich-5.0.2.data/data/include/* /tmp/kit/mp/include/
  target=/tmp/target-mpich
  [ -d $target/release ] || { mkdir -p $target && cp -a target/release $target/; }
  # mpi-sys's build script probed whichever MPI the seed was built with: probe again, for MPICH
  rm -rf $target/release/build/mpi-sys-* $target/release/.fingerprint/mpi-sys-*
  MPICC=/tmp/kit/mp/bin/mpicc CARGO_TARGET_DIR=$target cargo build --release --features mpi --bin lagra
  # cargo passes mpicc's library path to the link, not its rpath: the run sets LD_LIBRARY_PATH
  LD_LIBRARY_PATH=/tmp/kit/mp/lib:/tmp/kit/mp/lib/mpich ldd $target/release/lagra | grep -q '/tmp/kit/mp/lib/libmpi.so.12' ||
    { echo "the MPI build is not linked to the kit's MPICH" >&2; exit 1; }
  xz -T0 -3 -c $target/release/lagra > .devkit/lagra-mpi.xz
  du -sh .devkit; echo "carry: [\".devkit\"]   command: bash bench/sixteen_cores.sh"
  exit 0
fi

K=/tmp/kit
if [ ! -x $K/bin/lagra ] || [ -z "${QUICK:-}" ]; then
  rm -rf $K && mkdir -p $K && tar -xJf .devkit/kit.tar.xz -C $K
fi
[ -f .devkit/lagra-mpi.xz ] && xz -dc .devkit/lagra-mpi.xz > $K/bin/lagra-mpi && chmod +x $K/bin/lagra-mpi
export LD_LIBRARY_PATH=$K/lmp:$K/mp/lib:$K/mp/lib/mpich
L=$K/bin/lagra LMP=$K/lmp/lmp MPI=$K/mp/bin/mpirun W=/tmp/sixteen
rm -rf $W && mkdir -p $W && cp $K/peers/*.lmp $W/
exec > >(tee "${OUT:-/tmp}/sixteen.txt") 2>&1
# `lagra bench gradient` reads its scenes where it was built
[ -e /work/main/scenes/bench/lj_32k.lagra ] || { mkdir -p /work && ln -sfn "$root" /work/main; }

cpus=$(nproc); top=$((cpus - 1)); all=0-$top
if [ -n "${QUICK:-}" ]; then n=20 big=24 counts="1 2"; else n=40 big=64 counts="1 2 4 8 16"; fi
lscpu | grep -E 'Model name|^CPU\(s\)|Thread\(s\)'; echo "lagra $(git rev-parse --short HEAD 2>/dev/null)"
for c in $n $big; do for s in "" _checked _shifted; do
  sed "s/cells: \[20, 20, 20\]/cells: [$c, $c, $c]/" scenes/bench/lj_32k$s.lagra > $W/lj_$c$s.lagra; done; done

limit=150
field() { python3 -c "
import json, re, sys
r = json.load(open(sys.argv[1]))
m = re.search(r'spent ([0-9.]+) s of ([0-9.]+) s in exchanges', str(r.get('plan', '')))
print('wall %.3f s, checker %.3f, wait %.3f, serial %.3f, %.1f ns/atom-step, passed %s%s' % (r['wall_s'],
  r.get('checker_s', 0), r.get('checker_wait_s', 0), r.get('serial_s', 0), r.get('ns_per_atom_step') or 0,
  r.get('passed'), ', exchanges %s s' % m.group(1) if m else ''))" "$1" 2>/dev/null || echo "no result: $(tail -c 300 $W/err)"; }
lag() { # CPUS THREADS SCENE [STEPS]
  timeout $limit taskset -c "$1" $L run "$3" ${4:+--steps $4} --threads "$2" --json --quiet > $W/r.json 2> $W/err
  echo "lagra cpus $1 threads $2 $(basename "$3") ${4:-} steps: $(field $W/r.json)"; }
lmp() { # RANKS CELLS
  (cd $W && timeout $limit $MPI -np "$1" -bind-to core $LMP -in w1.lmp -var n "$2" -var nsteps 100 -sf opt \
    -log m.log -screen none > /dev/null 2>&1)
  echo "lammps-opt ranks $1 cells $2: $(awk '/Loop time of/ {printf "loop %.3f s, %.1f ns/atom-step", $4, $4/$9/$12*1e9}' $W/m.log)"
  rm -f $W/m.log; }
ranks() { # RANKS SCENE
  [ -x $K/bin/lagra-mpi ] || { echo "lagra ranks $1: no MPI build in the kit (bench/sixteen_cores.sh prepare)"; return; }
  timeout $limit $MPI -np "$1" -bind-to core $K/bin/lagra-mpi run "$2" --steps 100 --threads 1 --json --quiet --explain \
    > $W/r.json 2> $W/err
  echo "lagra ranks $1 $(basename "$2"): $(field $W/r.json)"; }

echo "== in.lj, threads beside LAMMPS-opt's ranks (39)"
for t in $counts; do [ "$t" -le "$cpus" ] || continue; lag 0-$((t - 1)) "$t" $W/lj_$n.lagra 100; lmp "$t" $n; done
lag $all "$cpus" $W/lj_$big.lagra 100; lmp "$cpus" $big
echo "== in.lj, Lagra's MPI ranks (41)"
for t in $counts; do [ "$t" -le "$cpus" ] && ranks "$t" $W/lj_$n.lagra; done
ranks "$cpus" $W/lj_$big.lagra
echo "== the checker's cost (39): without claims, then energy and momentum every 100 steps"
for s in _shifted _checked; do lag $all "$cpus" $W/lj_$n$s.lagra 100; done
for cpu in 0 0,1; do for s in _shifted _checked; do lag $cpu 1 scenes/bench/lj_32k$s.lagra 100; done; done
echo "== small scenes checked every step, one CPU against all (39), the default thread count"
for s in kepler earth_moon toy_hadron kremer_grest_polymer; do
  for cpu in 0 $all; do
    timeout $limit taskset -c $cpu $L run scenes/$s.lagra --json --quiet > $W/r.json 2> $W/err
    echo "small $s cpus $cpu: $(field $W/r.json)"
  done
done
echo "== the gradient's cost (39)"
for t in 1 "$cpus"; do
  timeout $limit taskset -c 0-$((t - 1)) $L bench gradient --threads "$t" 2>&1 | grep -E '^\| lj' | sed "s/^/threads $t /"
done
echo "== stack_1000 (42): one thread, two, all; then two one-thread copies at once"
for t in $(printf '%s\n' 1 2 "$cpus" | sort -nu); do lag 0-$((t - 1)) "$t" scenes/bench/stack_1000.lagra; done
copies=()
for cpu in 0 1; do
  timeout $limit taskset -c $cpu $L run scenes/bench/stack_1000.lagra --threads 1 --json --quiet > $W/copy$cpu.json 2> $W/err &
  copies+=($!)
done
wait "${copies[@]}" # not a bare `wait`: that waits for the tee above too, which never ends
for cpu in 0 1; do echo "stack copy on cpu $cpu: $(field $W/copy$cpu.json)"; done
echo "== done"
