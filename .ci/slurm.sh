#!/usr/bin/env bash
# Sweeps through a real scheduler: a single-node Slurm on this machine runs an example sweep as
# a job array (critterbox sweep --emit slurm), and the table collected from its shards must equal
# the same sweep run here (same rows, same hashes). Needs root and apt-get on a fresh Debian; on
# a machine where Slurm already answers, uses it and starts nothing. Stops only what it started.
# Expects the release binary built (cargo build --release -p critterbox-cli).
set -euo pipefail
cd "$(dirname "$0")/.."
started=$SECONDS
bin="$(realpath "${CARGO_TARGET_DIR:-target}")/release/critterbox"
sweep=scripts/sweeps/smoke.toml
[ -x "$bin" ] || { echo "no $bin: build it first (cargo build --release -p critterbox-cli)"; exit 1; }

work=$(mktemp -d /tmp/critterbox-slurm.XXXXXX)
pids=()
stop() {
  local status=$?
  if [ $status -ne 0 ]; then
    echo "-- slurm.sh failed; the daemons' logs and the tasks' output:"
    tail -n 20 "$work"/*.log "$work"/slurm-out/slurm/*.out 2>/dev/null || true
  fi
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
  done
  exit $status
}
trap stop EXIT

if ! command -v sbatch >/dev/null || ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  echo "-- installing slurm-wlm and munge"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq slurm-wlm munge >/dev/null
fi

if timeout 10 sinfo -h -o %T 2>/dev/null | grep -q .; then
  echo "-- a Slurm answers already: using it"
else
  # munge: the authentication Slurm's daemons and commands share.
  if ! munge -n 2>/dev/null | unmunge >/dev/null 2>&1; then
    if [ ! -s /etc/munge/munge.key ]; then
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1024 count=1 status=none
    fi
    chown munge:munge /etc/munge/munge.key && chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    # setpriv execs munged, so $! is munged itself.
    setpriv --reuid=munge --regid=munge --init-groups /usr/sbin/munged --foreground \
      >"$work/munged.log" 2>&1 &
    pids+=($!)
    for _ in $(seq 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.1; done
    munge -n | unmunge >/dev/null
  fi
  # A private configuration (SLURM_CONF): /etc/slurm is left as it is.
  host=$(hostname -s)
  mkdir -p "$work/state" "$work/spool"
  export SLURM_CONF="$work/slurm.conf"
  cat >"$SLURM_CONF" <<CONF
ClusterName=critterbox-ci
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  # No cgroup.conf: Debian's Slurm 22.05 runs without cgroups (see the notes on this set-up).
  slurmctld -D -i >"$work/slurmctld.out" 2>&1 &
  pids+=($!)
  sleep 1
  slurmd -D >"$work/slurmd.out" 2>&1 &
  pids+=($!)
  echo "-- waiting for the node to be idle"
  for _ in $(seq 60); do
    sinfo -h -o %T 2>/dev/null | grep -q idle && break
    sleep 1
  done
  sinfo -h -o %T | grep -q idle || { echo "the Slurm node never became idle"; sinfo || true; exit 1; }
fi
echo "-- Slurm up after $((SECONDS - started)) s"

# The sweep through Slurm: one array task per shard, each running its shard on one core.
"$bin" sweep "$sweep" --out "$work/slurm-out" --emit slurm --shards 4 --cpus 1
timeout 300 sbatch --wait "$work/slurm-out/sweep.sbatch"
"$bin" sweep "$sweep" --collect "$work/slurm-out"
# The same sweep here, in one process tree.
"$bin" sweep "$sweep" --out "$work/local"
python3 - "$work/slurm-out/results.csv" "$work/local/results.csv" <<'PY'
import csv, sys
def rows(path):
    with open(path, newline="") as f:
        # Wall time is the one figure that differs from run to run.
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(f)]
slurm, local = rows(sys.argv[1]), rows(sys.argv[2])
assert len(slurm) == len(local) == 8, (len(slurm), len(local))
assert all(r["outcome"] == "completed" for r in slurm), slurm
assert slurm == local, "the table collected from Slurm differs from the local sweep"
print(f"-- the Slurm table equals the local one: {len(slurm)} rows, same run and state hashes")
PY
echo "-- slurm.sh done in $((SECONDS - started)) s"
