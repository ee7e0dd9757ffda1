#!/usr/bin/env bash
# Hosts for multi-host tests: network namespaces on this machine, joined by veth pairs to a bridge, each running
# Debian's OpenSSH server with a key made for the test. Addresses come from 10.213.0.0/16, which exists only inside
# the test (nothing is routed anywhere else; the root namespace reaches the hosts through the bridge). The hosts
# share this machine's file system, so each gets a cache folder and a home of its own (LIGHTFARM_CACHE=DIR/cache-hI,
# HOME=DIR/home-hI), as separate machines would have: this machine's shell start-up files (a pyenv init costing
# 0.3 s per ssh session here) are not the hosts'.
#
#   hosts.sh up DIR N [ID]   make hosts 1..N (ID in 1..250 picks the subnet 10.213.ID.0/24; default: from DIR)
#                            and write DIR/ssh_config (Host h1..hN), DIR/hosts (name address per line),
#                            DIR/director_address (the bridge's address, which every host reaches)
#   hosts.sh down DIR        kill everything running in the hosts, remove them and the bridge (always safe)
#   hosts.sh pids DIR        processes still running in any host apart from the rig's daemons (sshd, slurmd), one
#                            "host pid cmd" per line
#   hosts.sh cut DIR I       cut host I off the network (its veth down); `hosts.sh mend DIR I` joins it again
#   hosts.sh kill DIR I      SIGKILL everything running in host I but its sshd listener
#
# Needs root (CAP_NET_ADMIN); exits 77 with a message when it cannot create a namespace.
set -euo pipefail
cmd=${1:?usage: hosts.sh up|down|pids DIR [N] [ID]}
dir=${2:?usage: hosts.sh up|down|pids DIR [N] [ID]}

# The kernel keeps one neighbour (ARP) table for all namespaces, 1,024 entries at most by default. Hosts that all
# talk to each other need about N x N (64 hosts: ~4,200), and past the limit the kernel drops address resolutions
# (dmesg: "neighbor table overflow"): connects time out, ssh fails, handshakes stall. `up` raises the limits while
# rigs are up; the last `down` puts back what was there.
neigh_saved=/run/lightfarm-rig-neigh
neigh_keys="net.ipv4.neigh.default.gc_thresh1 net.ipv4.neigh.default.gc_thresh2 net.ipv4.neigh.default.gc_thresh3"

raise_neighbour_limits() {
  local hosts=$1
  local need=$(( (hosts + 2) * (hosts + 2) * 2 ))
  # shellcheck disable=SC2086
  [ -f "$neigh_saved" ] || sysctl -n $neigh_keys 2>/dev/null | tr '\n' ' ' > "$neigh_saved" || return 0
  local k v want i=0
  for k in $neigh_keys; do
    i=$((i + 1))
    v=$(sysctl -n "$k" 2>/dev/null) || return 0
    want=$(( need * i / 3 ))
    if [ "$v" -lt "$want" ]; then
      sysctl -qw "$k=$want" 2>/dev/null || echo "hosts.sh: warning: cannot raise $k to $want (many hosts may lose packets)" >&2
    fi
  done
}

restore_neighbour_limits() {
  [ -f "$neigh_saved" ] || return 0
  ip -o link show type bridge 2>/dev/null | grep -q ": lfbr" && return 0  # another rig is still up
  local k i=0
  read -r -a saved < "$neigh_saved" || true
  for k in $neigh_keys; do
    [ -n "${saved[$i]:-}" ] && sysctl -qw "$k=${saved[$i]}" 2>/dev/null
    i=$((i + 1))
  done
  rm -f "$neigh_saved"
}

down() {
  [ -f "$dir/state" ] || return 0
  # shellcheck disable=SC1091
  . "$dir/state"
  for ns in $namespaces; do
    if ip netns list | grep -qw "$ns"; then
      for pid in $(ip netns pids "$ns" 2>/dev/null); do kill -9 "$pid" 2>/dev/null || true; done
      ip netns del "$ns" 2>/dev/null || true
    fi
  done
  ip link del "$bridge" 2>/dev/null || true
  rm -f "$dir/state"
  restore_neighbour_limits
}

pids() {
  [ -f "$dir/state" ] || return 0
  # shellcheck disable=SC1091
  . "$dir/state"
  local i=0
  for ns in $namespaces; do
    i=$((i + 1))
    # The daemons the rig started (sshd, and slurmd when tests/rig/slurm.sh runs) are not the farm's.
    local daemons
    daemons=" $(cat "$dir"/*.pid 2>/dev/null | tr '\n' ' ') "
    for pid in $(ip netns pids "$ns" 2>/dev/null); do
      [[ "$daemons" == *" $pid "* ]] && continue
      local cmdline
      cmdline=$(tr '\0' ' ' 2>/dev/null < "/proc/$pid/cmdline") || continue  # gone meanwhile
      echo "h$i $pid ${cmdline:0:120}"
    done
  done
}

up() {
  local n=${3:?hosts.sh up DIR N}
  local id=${4:-}
  mkdir -p "$dir"
  down
  if [ -z "$id" ]; then
    id=$(( $(cksum <<< "$dir" | cut -d' ' -f1) % 250 + 1 ))
    # The id a folder hashes to may be another rig's, or that of one whose namespaces the kernel is still tearing
    # down (their veths outlive `ip netns del` until the last process in them is reaped): "File exists". The next
    # free one then.
    for _ in $(seq 1 250); do
      if ! ip link show "lfbr$id" > /dev/null 2>&1 && ! ip -o link show | grep -q " lfv$id-"; then break; fi
      id=$(( id % 250 + 1 ))
    done
  fi
  local bridge="lfbr$id" namespaces=""
  if ! ip netns add "lfh$id-probe" 2>/dev/null; then
    echo "hosts.sh: cannot create network namespaces here (needs root with CAP_NET_ADMIN)" >&2
    exit 77
  fi
  # Some containers let a namespace be made but not entered ("mount --make-rslave /" failed): no rig there either.
  local entered
  if ! entered=$(ip netns exec "lfh$id-probe" true 2>&1); then
    ip netns del "lfh$id-probe" 2>/dev/null || true
    echo "hosts.sh: cannot enter a network namespace here: $entered" >&2
    exit 77
  fi
  ip netns del "lfh$id-probe"
  for i in $(seq 1 "$n"); do namespaces="$namespaces lfh$id-$i"; done
  printf 'bridge=%s\nnamespaces="%s"\n' "$bridge" "$namespaces" > "$dir/state"
  trap 'down; exit 1' ERR
  raise_neighbour_limits "$n"
  ip link add "$bridge" type bridge
  ip addr add "10.213.$id.1/24" dev "$bridge"
  ip link set "$bridge" up
  echo "10.213.$id.1" > "$dir/director_address"

  [ -f "$dir/id" ] || ssh-keygen -q -t ed25519 -N '' -f "$dir/id"
  [ -f "$dir/host_key" ] || ssh-keygen -q -t ed25519 -N '' -f "$dir/host_key"
  cp "$dir/id.pub" "$dir/authorized_keys"
  chmod 600 "$dir/authorized_keys"
  mkdir -p /run/sshd
  : > "$dir/hosts"
  : > "$dir/ssh_config"
  local i=0
  for ns in $namespaces; do
    i=$((i + 1))
    local addr="10.213.$id.$((i + 10))"
    mkdir -p "$dir/home-h$i"
    ip netns add "$ns"
    ip link add "lfv$id-$i" type veth peer name eth0 netns "$ns"
    ip link set "lfv$id-$i" master "$bridge" up
    ip -n "$ns" addr add "$addr/24" dev eth0
    ip -n "$ns" link set eth0 up
    ip -n "$ns" link set lo up
    ip netns exec "$ns" /usr/sbin/sshd -h "$dir/host_key" -o "ListenAddress=$addr" -o "PidFile=$dir/sshd-$i.pid" \
      -o "AuthorizedKeysFile=$dir/authorized_keys" -o PermitRootLogin=prohibit-password -o PasswordAuthentication=no \
      -o UsePAM=no -o StrictModes=no -o MaxSessions=64 -o MaxStartups=64:30:128 \
      -o "SetEnv=LIGHTFARM_RIG=$ns LIGHTFARM_CACHE=$dir/cache-h$i HOME=$dir/home-h$i"
    echo "h$i $addr" >> "$dir/hosts"
    cat >> "$dir/ssh_config" <<CFG
Host h$i $addr
  HostName $addr
  User root
  IdentityFile $dir/id
  IdentitiesOnly yes
  UserKnownHostsFile /dev/null
  StrictHostKeyChecking no
  LogLevel ERROR
CFG
  done
  # Wait until every sshd answers.
  for i in $(seq 1 "$n"); do
    for _ in $(seq 1 50); do
      ssh -F "$dir/ssh_config" -o BatchMode=yes -o ConnectTimeout=2 "h$i" true 2>/dev/null && break
      sleep 0.1
    done
  done
  trap - ERR
}

veth() {
  # shellcheck disable=SC1091
  . "$dir/state"
  echo "lfv${bridge#lfbr}-$1"
}

case "$cmd" in
  up) up "$@" ;;
  cut) ip link set "$(veth "${3:?hosts.sh cut DIR I}")" down ;;
  mend) ip link set "$(veth "${3:?hosts.sh mend DIR I}")" up ;;
  kill) pids | awk -v h="h${3:?hosts.sh kill DIR I}" '$1 == h { print $2 }' | xargs -r kill -9 2>/dev/null || true ;;
  down) down ;;
  pids) pids ;;
  *) echo "hosts.sh: unknown command '$cmd'" >&2; exit 2 ;;
esac
