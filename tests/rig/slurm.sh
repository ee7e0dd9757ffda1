#!/usr/bin/env bash
# A real Slurm cluster over the namespace hosts of tests/rig/hosts.sh: a private munged (its own key and socket),
# slurmctld in this namespace on the bridge address, one slurmd per host in its namespace (with a private cgroup v1
# mount, since `ip netns exec` gives it a fresh /sys). Nodes are named h1..hN, partition "lf".
#
#   slurm.sh up DIR [K]  DIR holds a rig made by `hosts.sh up DIR N`; slurmd on its first K hosts (default all N);
#                        writes DIR/slurm.conf (export SLURM_CONF)
#   slurm.sh down DIR    stops the daemons (always safe)
#
# Exits 77 with a message when Slurm or munge is not installed, or slurmd cannot run in a namespace here.
set -euo pipefail
cmd=${1:?usage: slurm.sh up|down DIR}
dir=${2:?usage: slurm.sh up|down DIR}
nodes=${3:-}

down() {
  for f in "$dir"/slurmd-*.pid "$dir/slurmctld.pid" "$dir/munged.pid"; do
    [ -f "$f" ] && kill "$(cat "$f")" 2>/dev/null || true
  done
  sleep 0.2
  for f in "$dir"/slurmd-*.pid "$dir/slurmctld.pid" "$dir/munged.pid"; do
    [ -f "$f" ] && kill -9 "$(cat "$f")" 2>/dev/null || true
    rm -f "$f"
  done
}

up() {
  for tool in slurmctld slurmd munged mungekey srun; do
    command -v "$tool" >/dev/null || { echo "slurm.sh: $tool is not installed (slurm-wlm, munge)" >&2; exit 77; }
  done
  # shellcheck disable=SC1091
  . "$dir/state"
  local subnet ctl n
  ctl=$(cat "$dir/director_address")
  subnet=${ctl%.1}
  n=$(wc -l < "$dir/hosts")
  n=${nodes:-$n}
  down
  mkdir -p "$dir/slurm/ctld" "$dir/slurm/log"
  [ -f "$dir/munge.key" ] || mungekey -c -k "$dir/munge.key"
  chmod 600 "$dir/munge.key"
  munged --force --socket="$dir/munge.sock" --key-file="$dir/munge.key" --pid-file="$dir/munged.pid" \
    --seed-file="$dir/munge.seed" --log-file="$dir/slurm/log/munged.log"
  {
    echo "ClusterName=lftest"
    echo "SlurmctldHost=$(hostname)($ctl)"
    # Ports of this rig's subnet, so that two rigs (or a real cluster on 6817) never answer each other.
    local id=${subnet##*.}
    echo "SlurmctldPort=$((20000 + 2 * id))"
    echo "SlurmdPort=$((20001 + 2 * id))"
    echo "SlurmUser=root"
    echo "SlurmdUser=root"
    echo "AuthType=auth/munge"
    echo "AuthInfo=socket=$dir/munge.sock"
    echo "StateSaveLocation=$dir/slurm/ctld"
    echo "SlurmdSpoolDir=$dir/slurm/spool-%n"
    echo "SlurmctldPidFile=$dir/slurmctld.pid"
    echo "SlurmdPidFile=$dir/slurmd-%n.pid"
    echo "SlurmctldLogFile=$dir/slurm/log/slurmctld.log"
    echo "SlurmdLogFile=$dir/slurm/log/slurmd-%n.log"
    echo "ProctrackType=proctrack/linuxproc"
    echo "TaskPlugin=task/none"
    echo "JobAcctGatherType=jobacct_gather/none"
    echo "AccountingStorageType=accounting_storage/none"
    echo "SchedulerType=sched/builtin"
    echo "SelectType=select/cons_tres"
    echo "SelectTypeParameters=CR_Core"
    echo "MpiDefault=none"
    echo "ReturnToService=2"
    for i in $(seq 1 "$n"); do
      echo "NodeName=h$i NodeAddr=$subnet.$((i + 10)) CPUs=$(nproc) State=UNKNOWN"
    done
    echo "PartitionName=lf Nodes=h[1-$n] Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES"
  } > "$dir/slurm.conf"
  # slurmd needs a cgroup file system, and `ip netns exec` gives it a fresh /sys: mount one there, privately, of the
  # kind this machine has (v1 controllers on a hybrid host, the unified hierarchy on a v2-only one).
  local mounts
  if grep -q '^0::' /proc/self/cgroup && [ "$(wc -l < /proc/self/cgroup)" -eq 1 ]; then
    printf 'CgroupPlugin=cgroup/v2\nIgnoreSystemd=yes\n' > "$dir/cgroup.conf"
    mounts="mount -t cgroup2 none /sys/fs/cgroup"
  else
    echo "CgroupPlugin=cgroup/v1" > "$dir/cgroup.conf"
    mounts="mount -t tmpfs cgroup_root /sys/fs/cgroup && for c in freezer cpuset memory devices; do \
      mkdir -p /sys/fs/cgroup/\$c && mount -t cgroup -o \$c \$c /sys/fs/cgroup/\$c; done"
  fi
  export SLURM_CONF="$dir/slurm.conf"
  slurmctld -f "$dir/slurm.conf"
  local i=0
  for ns in $namespaces; do
    i=$((i + 1))
    [ "$i" -le "$n" ] || break
    ip netns exec "$ns" sh -c "$mounts; exec slurmd -f '$dir/slurm.conf' -N h$i"
  done
  # Every node idle before anyone asks for it.
  for _ in $(seq 1 100); do
    if [ "$(sinfo -h -o '%t' 2>/dev/null | sort -u)" = "idle" ]; then return 0; fi
    sleep 0.1
  done
  echo "slurm.sh: the nodes did not come up:" >&2
  sinfo >&2 || true
  tail -5 "$dir/slurm/log/slurmd-h1.log" >&2 || true
  down
  # A slurmd that cannot start inside a namespace on this kernel (cgroups) is a limit of the machine, not a bug.
  if grep -qiE 'cgroup|hybrid' "$dir/slurm/log/slurmd-h1.log" 2>/dev/null; then exit 77; fi
  exit 1
}

case "$cmd" in
  up) up ;;
  down) down ;;
  *) echo "slurm.sh: unknown command '$cmd'" >&2; exit 2 ;;
esac
