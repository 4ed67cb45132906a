#!/usr/bin/env bash
# The farm path on a real scheduler: a one-node Slurm (this host) runs the
# job array that `groombake batch MANIFEST --emit slurm` writes, and its
# outputs must be byte-identical to `groombake batch MANIFEST --jobs 2`.
# Then one task alone (`sbatch --array=3`, as a TD resubmits a failed or
# deleted job) must bake job 3 again, byte-identical, and merge.
#
# Usage: .ci/slurm_test.sh GROOMBAKE_BINARY
# Needs root (slurmctld and slurmd run as root). Installs Debian's slurm-wlm
# and munge when they are missing; exits 77 (skipped) only when they cannot
# be installed. Everything else (munge key, socket, slurm.conf, state) lives
# in a temporary folder on ports of its own; the daemons are stopped at exit.
set -euo pipefail
exe=$(realpath "$1")
root=$(cd "$(dirname "$0")/.." && pwd)

skip() { echo "SLURM TEST SKIPPED: $*"; exit 77; }
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  [ "$(id -u)" = 0 ] || skip "slurm-wlm/munge are not installed and this user cannot install them"
  command -v apt-get >/dev/null || skip "slurm-wlm/munge are not installed and there is no apt-get"
  echo "installing slurm-wlm and munge (apt-get)"
  { apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge; } \
    >/dev/null || skip "apt-get could not install slurm-wlm and munge"
fi
[ "$(id -u)" = 0 ] || { echo "the Slurm test needs root (slurmd)"; exit 1; }

work=$(mktemp -d /tmp/groombake-slurm.XXXXXX)
chmod 755 "$work"
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  sleep 1
  for pid in "${pids[@]}"; do kill -9 "$pid" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

# munge: a key and socket of its own.
mkdir -p "$work/munge"
chmod 700 "$work/munge"
dd if=/dev/urandom of="$work/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$work/munge/munge.key"
munged --force --key-file="$work/munge/munge.key" --socket="$work/munge/socket" \
  --pid-file="$work/munge/munged.pid" --log-file="$work/munge/munged.log" \
  --seed-file="$work/munge/seed"
pids+=("$(cat "$work/munge/munged.pid")")

# Slurm: one node, this host, all its CPUs.
host=$(hostname -s)
port=${GROOMBAKE_SLURM_PORT:-16817}
mkdir -p "$work/state" "$work/spool"
export SLURM_CONF="$work/slurm.conf"
cat > "$SLURM_CONF" <<CONF
ClusterName=groombake-ci
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$work/munge/socket
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$work/jobcomp.log
MpiDefault=none
ReturnToService=2
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$host CPUs=$(nproc) RealMemory=$(free -m | awk '/^Mem:/ {print $2}') State=UNKNOWN
PartitionName=ci Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
slurmctld -c -f "$SLURM_CONF" -i
sleep 1
pids+=("$(cat "$work/slurmctld.pid")")
slurmd -f "$SLURM_CONF"
sleep 1
pids+=("$(cat "$work/slurmd.pid")")

ready=0
for _ in $(seq 60); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed)'; then ready=1; break; fi
  sleep 1
done
sinfo || true
if [ "$ready" != 1 ]; then
  echo "the Slurm node did not come up"; tail -20 "$work/slurmctld.log" "$work/slurmd.log" || true
  exit 1
fi

# The manifest: the four samples x three small grooms, twice (two output folders).
cd "$work"
for n in 4 6 8; do "$exe" generate swatch -o "g$n.hair" --strands "$n" --length 0.1 >/dev/null; done
for out in local farm; do
  : > "$out.toml"
  echo "out = \"$out\"" >> "$out.toml"
  for s in bed_hair blow_dry perm wind; do
    printf '[[glob]]\ntimeline = "%s"\ngrooms = "g*.hair"\n' "$root/samples/$s.toml" >> "$out.toml"
  done
done

echo "== local: groombake batch local.toml --jobs 2"
"$exe" batch local.toml --jobs 2 -q

echo "== farm: groombake batch farm.toml --emit slurm --time 00:30:00 --mem 1G --partition ci > bake.sbatch; sbatch bake.sbatch"
"$exe" batch farm.toml --emit slurm --time 00:30:00 --mem 1G --partition ci > bake.sbatch
grep '^#SBATCH' bake.sbatch
array=$(sbatch --parsable bake.sbatch)
echo "submitted array job $array"
squeue -a -o '%.18i %.12j %.8T %.10M %R' || true

# Wait (bounded) until the array and its merge have left the queue.
wait_for_queue() {
  local deadline=$(( $(date +%s) + ${GROOMBAKE_SLURM_TIMEOUT:-900} ))
  while [ -n "$(squeue -h -a -o %i 2>/dev/null)" ]; do
    if [ "$(date +%s)" -gt "$deadline" ]; then
      echo "timed out waiting for the array"; squeue -a; tail -30 "$work/slurmctld.log"; exit 1
    fi
    sleep 2
  done
}
wait_for_queue

echo "== completed jobs (jobcomp log: one line per job and array task)"
cat "$work/jobcomp.log"
tasks=$(grep -c " Name=groombake .* ArrayJobId=$array " "$work/jobcomp.log" || true)
ok_tasks=$(grep -c " Name=groombake JobState=COMPLETED .* ArrayJobId=$array ArrayTaskId=[0-9]* DerivedExitCode=0:0 ExitCode=0:0" "$work/jobcomp.log" || true)
merges=$(grep -c " Name=groombake-merge JobState=COMPLETED .* ExitCode=0:0" "$work/jobcomp.log" || true)
echo "array tasks: $tasks, completed: $ok_tasks; merge jobs completed: $merges"
echo "== array task logs (first lines)"
for log in farm/slurm/*.log; do echo "-- $log"; head -3 "$log"; done

status=0
[ "$tasks" -eq 12 ] && [ "$ok_tasks" -eq 12 ] || { echo "expected 12 completed array tasks"; status=1; }
# The script's requests reached the scheduler (TimeLimit in minutes).
limited=$(grep -c " Name=groombake .* Partition=ci TimeLimit=30 .* ArrayJobId=$array " "$work/jobcomp.log" || true)
[ "$limited" -eq 12 ] || { echo "expected 12 tasks on partition ci with a 30-minute limit, got $limited"; status=1; }
[ "$merges" -eq 1 ] || { echo "expected one completed merge job"; status=1; }
[ -f farm/batch_report.json ] || { echo "no merged report farm/batch_report.json"; status=1; }
grep -q '"succeeded": 12' farm/batch_report.json || { echo "the merged report does not list 12 succeeded jobs"; status=1; }

echo "== byte comparison of every output (job reports and logs left out)"
compared=0
while IFS= read -r -d '' file; do
  rel=${file#local/}
  if ! cmp -s "$file" "farm/$rel"; then echo "DIFFERS: $rel"; status=1; fi
  compared=$((compared + 1))
done < <(find local -type f ! -name groombake_job.json ! -name batch_report.json ! -name batch_report.html -print0 | sort -z)
extra=$(find farm -type f ! -name groombake_job.json ! -name batch_report.json ! -name batch_report.html ! -path 'farm/slurm/*' | wc -l)
[ "$extra" -eq "$compared" ] || { echo "farm has $extra outputs, local $compared"; status=1; }
echo "compared $compared output files byte for byte"
[ "$compared" -ge 24 ] || { echo "too few outputs"; status=1; }

# Job 3 (blow_dry-g4: the manifest's globs in order, grooms sorted) deleted
# and baked again by a resubmit of its task alone.
echo "== single-task resubmit: rm -r farm/blow_dry-g4; sbatch --array=3 bake.sbatch"
rm -r farm/blow_dry-g4 farm/batch_report.json
single=$(sbatch --parsable --array=3 bake.sbatch)
echo "submitted array job $single (task 3 only)"
wait_for_queue
grep " ArrayJobId=$single " "$work/jobcomp.log" || true
single_ok=$(grep -c " Name=groombake JobState=COMPLETED .* ArrayJobId=$single ArrayTaskId=3 DerivedExitCode=0:0 ExitCode=0:0" "$work/jobcomp.log" || true)
merges=$(grep -c " Name=groombake-merge JobState=COMPLETED .* ExitCode=0:0" "$work/jobcomp.log" || true)
echo "task 3 completed: $single_ok; merge jobs completed: $merges"
[ "$single_ok" -eq 1 ] || { echo "the resubmitted task 3 did not complete"; status=1; }
[ "$merges" -eq 2 ] || { echo "the resubmitted task did not merge the reports"; status=1; }
grep -q '"succeeded": 12' farm/batch_report.json 2>/dev/null || { echo "after the resubmit the merged report does not list 12 succeeded jobs"; status=1; }
resubmitted=0
while IFS= read -r -d '' file; do
  rel=${file#local/}
  if ! cmp -s "$file" "farm/$rel"; then echo "DIFFERS after the resubmit: $rel"; status=1; fi
  resubmitted=$((resubmitted + 1))
done < <(find local/blow_dry-g4 -type f ! -name groombake_job.json -print0 | sort -z)
echo "compared $resubmitted output files of the resubmitted job byte for byte"
[ "$resubmitted" -ge 2 ] || { echo "too few outputs of the resubmitted job"; status=1; }

[ "$status" = 0 ] && echo "SLURM TEST PASSED" || echo "SLURM TEST FAILED"
exit "$status"
