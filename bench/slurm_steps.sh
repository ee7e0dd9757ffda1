#!/usr/bin/env bash
# Inside a Slurm allocation of nodes h1..h3 (run under salloc): how long N processes take to start as N one-task
# job steps (how SlurmLauncher starts actors) vs as one step per node that starts that node's share itself.
# Prints "per_actor SECONDS per_node SECONDS" (launch to the last process running).
set -euo pipefail
n=${1:-12}
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
now() { date +%s.%N; }
t0=$(now)
for i in $(seq 1 "$n"); do
  srun --overlap --nodelist=h$(( (i - 1) % 3 + 1 )) --nodes=1 --ntasks=1 --quiet sh -c "date +%s.%N > $d/a$i" &
done
wait
per_actor=$(echo "$(cat "$d"/a* | sort -n | tail -1) - $t0" | bc)
t0=$(now)
for h in 1 2 3; do
  srun --overlap --nodelist=h$h --nodes=1 --ntasks=1 --quiet \
    sh -c "for j in $(seq -s ' ' 1 $((n / 3))); do date +%s.%N > $d/b$h-\$j & done; wait" &
done
wait
per_node=$(echo "$(cat "$d"/b* | sort -n | tail -1) - $t0" | bc)
echo "per_actor $per_actor per_node $per_node"
