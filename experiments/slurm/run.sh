#!/usr/bin/env bash
# Does a sweep run as a Slurm array job give the unsharded sweep's results?
#
# Installs Slurm and MUNGE from the distribution's packages (Debian:
# slurm-wlm, munge; needs root), starts a single-node cluster on this
# machine (munged, slurmctld, slurmd with a minimal slurm.conf for
# localhost, all in a scratch directory, on ports 16817/16818), runs the
# sweep unsharded, writes the Slurm scripts with `posg-fsc sweep --slurm`,
# submits the array job and the dependent merge, waits, compares
# sweep.csv (apart from the timing column) and sweep.svg, stops the daemons
# it started by process id, and writes results/slurm.csv.
#
# Usage: experiments/slurm/run.sh   (POSG_FSC=path skips the release build;
# SHARDS, DEF_NODES, ADV_NODES, MAX_ITERATIONS change the sweep)
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
SHARDS=${SHARDS:-3}
DEF_NODES=${DEF_NODES:-1..3}
ADV_NODES=${ADV_NODES:-1..3}
MAX_ITERATIONS=${MAX_ITERATIONS:-20}
SEED=1
FORMULA='F goal & G !unsafe'

now() { date +%s.%N; }
elapsed() { python3 -c "print(f'{$2 - $1:.2f}')"; }

if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends slurm-wlm munge
fi
if [ -z "${POSG_FSC:-}" ]; then
  cargo build --release --quiet
  POSG_FSC=$ROOT/target/release/posg-fsc
fi
POSG_FSC=$(realpath "$POSG_FSC")

WORK=$(mktemp -d /tmp/posg-fsc-slurm.XXXXXX)
chmod 755 "$WORK"
mkdir -p "$WORK/munge" "$WORK/state" "$WORK/spool" "$WORK/log"
chmod 700 "$WORK/munge"
PIDS=()
stop() {
  for pid in "${PIDS[@]}"; do
    kill "$pid" 2>/dev/null || true
  done
  for pid in "${PIDS[@]}"; do
    wait "$pid" 2>/dev/null || true
  done
}
trap stop EXIT

# MUNGE: a fresh key, its own socket.
dd if=/dev/urandom of="$WORK/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$WORK/munge/munge.key"
SOCKET=$WORK/munge/munge.socket
cluster_start=$(now)
munged --foreground --force --socket="$SOCKET" --key-file="$WORK/munge/munge.key" \
  --log-file="$WORK/log/munged.log" --pid-file="$WORK/munge/munged.pid" \
  --seed-file="$WORK/munge/munged.seed" 2>>"$WORK/log/munged.stderr" &
PIDS+=($!)
for _ in $(seq 50); do [ -S "$SOCKET" ] && break; sleep 0.1; done

# Slurm: one node with this machine's CPUs and memory (`slurmd -C`).
HOST=$(hostname -s)
NODE=$(slurmd -C | head -1 | sed "s/^NodeName=[^ ]*/NodeName=posgnode NodeAddr=127.0.0.1/")
export SLURM_CONF=$WORK/slurm.conf
cat >"$SLURM_CONF" <<EOF
ClusterName=posgfsc
SlurmctldHost=$HOST(127.0.0.1)
SlurmUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$SOCKET
CredType=cred/munge
StateSaveLocation=$WORK/state
SlurmdSpoolDir=$WORK/spool
SlurmctldPidFile=$WORK/slurmctld.pid
SlurmdPidFile=$WORK/slurmd.pid
SlurmctldLogFile=$WORK/log/slurmctld.log
SlurmdLogFile=$WORK/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
$NODE State=UNKNOWN
PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D -i -f "$SLURM_CONF" >"$WORK/log/slurmctld.stderr" 2>&1 &
PIDS+=($!)
slurmd -D -N posgnode -f "$SLURM_CONF" >"$WORK/log/slurmd.stderr" 2>&1 &
PIDS+=($!)
ready=
for _ in $(seq 100); do
  if sinfo -h -N -o '%T' 2>/dev/null | grep -qx idle; then ready=1; break; fi
  sleep 0.2
done
if [ -z "$ready" ]; then
  echo "the single-node cluster did not come up; logs in $WORK/log" >&2
  tail -n 20 "$WORK"/log/* >&2 || true
  exit 1
fi
cluster_seconds=$(elapsed "$cluster_start" "$(now)")
echo "cluster up in $cluster_seconds s ($(sinfo -h -o '%P %D %C'))"

# The sweep, unsharded and as a Slurm array job.
"$POSG_FSC" example grid --out "$WORK/grid.posg.json" >/dev/null
SWEEP=(sweep "$WORK/grid.posg.json" --ltl "$FORMULA" --def-nodes "$DEF_NODES"
  --adv-nodes "$ADV_NODES" --max-iterations "$MAX_ITERATIONS" --seed "$SEED" --quiet)
start=$(now)
"$POSG_FSC" "${SWEEP[@]}" --out "$WORK/whole" >/dev/null
unsharded_seconds=$(elapsed "$start" "$(now)")
echo "unsharded sweep: $unsharded_seconds s"

"$POSG_FSC" "${SWEEP[@]}" --out "$WORK/sharded" --slurm --shards "$SHARDS" \
  --slurm-option=--time=0:30:00
start=$(now)
JOBID=$(sbatch --parsable "$WORK/sharded/sweep.sbatch")
JOBID=${JOBID%%;*}
MERGE=$(sbatch --parsable --wait --dependency=afterok:"$JOBID" "$WORK/sharded/sweep-merge.sbatch")
slurm_seconds=$(elapsed "$start" "$(now)")
echo "array job $JOBID and merge job ${MERGE%%;*}: $slurm_seconds s from submission to the merge's end"
cat "$WORK"/sharded/slurm-logs/merge-*.out

python3 - "$WORK" "$ROOT/results/slurm.csv" <<EOF
import csv, glob, json, os, subprocess, sys
work, out = sys.argv[1], sys.argv[2]
def rows(d):
    with open(os.path.join(d, "sweep.csv")) as f:
        r = list(csv.DictReader(f))
    return [{k: v for k, v in row.items() if k != "seconds"} for row in r]
whole, sharded = rows(f"{work}/whole"), rows(f"{work}/sharded")
rows_equal = whole == sharded and len(whole) > 0
svg_equal = open(f"{work}/whole/sweep.svg").read() == open(f"{work}/sharded/sweep.svg").read()
per_shard = []
for record in sorted(glob.glob(f"{work}/sharded/shards/shard-*.json")):
    plan = json.load(open(record))
    k = plan["written_by"].split()[1]
    seconds = sum(json.load(open(p))["seconds"]
                  for m in [a for i, a in enumerate(plan["plan"]["adversary_sizes"])
                            if i % plan["plan"]["shards"] == int(k.split("/")[0]) - 1]
                  for p in glob.glob(f"{work}/sharded/def*-adv{m}/summary.json"))
    per_shard.append(f"{k}:{seconds:.2f}")
version = subprocess.run(["$POSG_FSC", "--version"], capture_output=True, text=True).stdout.split()[-1]
slurm = subprocess.run(["slurmctld", "-V"], capture_output=True, text=True).stdout.split()[-1]
fields = {
    "posg_fsc_version": version, "slurm_version": slurm, "game": "example grid (3x2)",
    "formula": "$FORMULA", "def_nodes": "$DEF_NODES", "adv_nodes": "$ADV_NODES",
    "max_iterations": $MAX_ITERATIONS, "seed": $SEED, "pairs": len(whole), "shards": $SHARDS,
    "cpus": os.cpu_count(), "cluster_start_seconds": $cluster_seconds,
    "unsharded_seconds": $unsharded_seconds, "slurm_seconds": $slurm_seconds,
    "solve_seconds_per_shard": " ".join(per_shard),
    "rows_equal_apart_from_seconds": rows_equal, "svg_equal": svg_equal,
}
with open(out, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(fields))
    w.writeheader()
    w.writerow(fields)
print(f"rows equal: {rows_equal}, sweep.svg equal: {svg_equal}; wrote {out}")
sys.exit(0 if rows_equal and svg_equal else 1)
EOF
stop
trap - EXIT
rm -rf "$WORK"
