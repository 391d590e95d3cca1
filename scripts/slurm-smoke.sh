#!/usr/bin/env bash
# A real cluster run on one machine (issue 17.6): docs/batch.md's Slurm job array,
# unchanged, on a single-node Slurm (slurmctld + slurmd on this host, munge
# authentication), over data/svg with 3 shards; then the doc's merge job (and the
# report page of the whole); then a check that every data/svg file has exactly one
# row in the merged report and one card in the page's gallery.
#
#   scripts/slurm-smoke.sh            # as root on Debian (installs slurm-wlm, munge)
#
# Environment: TRIWILD (the binary; default target/release/triwild, built when
# missing), DATA (default data/svg), SHARDS (default 3), KEEP=1 keeps the work dir.
# Starts its own daemons with a private config and state under a temporary
# directory, and stops them on exit (whatever the outcome). Exit 0 pass, 1 fail.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
REPO=$PWD

say() { printf '=== %s\n' "$*"; }
fail() { printf 'FAIL: %s\n' "$*" >&2; exit 1; }

SHARDS=${SHARDS:-3}
DATA=$(realpath "${DATA:-data/svg}")
TRIWILD=${TRIWILD:-$REPO/target/release/triwild}

# --- packages -----------------------------------------------------------------
need=()
for cmd in slurmctld:slurmctld slurmd:slurmd sbatch:slurm-client munged:munge; do
  command -v "${cmd%%:*}" >/dev/null 2>&1 || need+=("${cmd#*:}")
done
if [ "${#need[@]}" -ne 0 ]; then
  [ "$(id -u)" -eq 0 ] || fail "missing ${need[*]} (install slurm-wlm and munge, or run as root)"
  say "installing slurm-wlm munge"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq && apt-get install -y -qq slurm-wlm munge >/dev/null
fi
[ "$(id -u)" -eq 0 ] || fail "run as root (slurmd starts jobs as their users)"

if [ ! -x "$TRIWILD" ]; then
  say "building $TRIWILD"
  cargo build --release --features cli --locked
fi
TRIWILD=$(realpath "$TRIWILD")

# --- the private cluster ----------------------------------------------------------
WORK=$(mktemp -d /tmp/triwild-slurm.XXXXXX)
chmod 755 "$WORK"
STATE=$WORK/state
mkdir -p "$STATE/ctld" "$STATE/d" "$WORK/logs"
export SLURM_CONF=$WORK/slurm.conf
pids=()

cleanup() {
  local rc=$?
  set +e
  if [ -n "${SLURM_CONF:-}" ] && [ -f "$SLURM_CONF" ]; then
    scancel --quiet --user="$(id -un)" 2>/dev/null
  fi
  for pid in "${pids[@]}"; do
    kill "$pid" 2>/dev/null
  done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null
  done
  if [ "$rc" -ne 0 ]; then
    for log in "$STATE"/*.log "$STATE"/*.out "$WORK"/logs/*; do
      [ -f "$log" ] && { echo "--- $log (tail)"; tail -n 20 "$log"; }
    done
  fi
  if [ "${KEEP:-0}" = 1 ]; then echo "work dir kept: $WORK"; else rm -rf "$WORK"; fi
  say "daemons stopped; exit $rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# munge: a key (created if missing), and a daemon of our own unless one answers.
if ! munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1; then
  if [ ! -s /etc/munge/munge.key ]; then
    say "creating a munge key"
    if command -v mungekey >/dev/null 2>&1; then
      mungekey --create --keyfile=/etc/munge/munge.key
    else
      dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    fi
  fi
  chown munge:munge /etc/munge /etc/munge/munge.key
  chmod 700 /etc/munge
  chmod 400 /etc/munge/munge.key
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  say "starting munged"
  runuser -u munge -- munged --foreground >>"$STATE/munged.log" 2>&1 &
  pids+=($!)
  for _ in $(seq 50); do
    munge -n </dev/null 2>/dev/null | unmunge >/dev/null 2>&1 && break
    sleep 0.2
  done
  munge -n </dev/null | unmunge >/dev/null || fail "munged does not answer"
fi

HOST=$(hostname -s)
CPUS=$(nproc)
# Ports of our own, so a Slurm already on this machine is left alone.
PORT=${SLURM_SMOKE_PORT:-16817}
cat >"$SLURM_CONF" <<EOF
ClusterName=triwild-smoke
SlurmctldHost=$HOST(127.0.0.1)
SlurmctldPort=$PORT
SlurmdPort=$((PORT + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
StateSaveLocation=$STATE/ctld
SlurmdSpoolDir=$STATE/d
SlurmctldPidFile=$STATE/slurmctld.pid
SlurmdPidFile=$STATE/slurmd.pid
SlurmctldLogFile=$STATE/slurmctld.log
SlurmdLogFile=$STATE/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
MinJobAge=600
NodeName=$HOST NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=2048 State=UNKNOWN
PartitionName=smoke Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF

say "starting slurmctld and slurmd ($HOST, $CPUS CPUs, config $SLURM_CONF)"
slurmctld -D -c -f "$SLURM_CONF" >>"$STATE/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$SLURM_CONF" >>"$STATE/slurmd.out" 2>&1 &
pids+=($!)

state=""
for _ in $(seq 120); do
  state=$(sinfo -h -N -n "$HOST" -o %t 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.5
done
[ "$state" = idle ] || { sinfo -R || true; fail "node $HOST not idle after 60 s (state '$state')"; }
sinfo

# --- docs/batch.md's array script, as written ---------------------------------
# The one ```sh block with #SBATCH lines; its #SBATCH sizes are for a big cluster,
# so this run overrides them on the sbatch command line (which wins over #SBATCH)
# and gives the script its IN, OUT and TRIWILD through the environment.
awk '/^```sh$/ {inblk=1; blk=""; next}
     /^```$/ && inblk {inblk=0; if (blk ~ /#SBATCH/) printf "%s", blk; next}
     inblk {blk = blk $0 "\n"}' docs/batch.md >"$WORK/triwild-array.sh"
grep -q '^#SBATCH --array' "$WORK/triwild-array.sh" || fail "no Slurm array script found in docs/batch.md"
chmod +x "$WORK/triwild-array.sh"

OUT=$WORK/out
mkdir -p "$OUT"
say "submitting the array: $SHARDS shards over $DATA"
jid=$(cd "$WORK" && IN=$DATA OUT=$OUT TRIWILD=$TRIWILD sbatch --parsable \
  --array=1-"$SHARDS" --cpus-per-task=1 --mem=1G --time=00:30:00 \
  --output="$WORK/logs/triwild-%A_%a.out" triwild-array.sh)
jid=${jid%%;*}
echo "array job $jid"

# The doc's merge step: a job that runs after every task (afterany); --wait
# returns when it has finished.
say "merging the shard reports (a dependent job)"
merge="$TRIWILD batch --merge-reports $OUT/report.shard-*-of-$SHARDS.jsonl -o $OUT/report.jsonl"
# and the page of the whole collection from the merged report (issue 40)
merge="$merge && $TRIWILD report $OUT/report.jsonl -o $OUT/report.html"
merge_rc=0
(cd "$WORK" && sbatch --wait --dependency=afterany:"$jid" --mem=256M --time=00:10:00 \
  --output="$WORK/logs/merge-%j.out" --wrap "$merge") || merge_rc=$?

# --- checks -------------------------------------------------------------------------
failed=0
for k in $(seq 1 "$SHARDS"); do
  info=$(scontrol -o show job "${jid}_$k" 2>/dev/null || true)
  st=$(grep -o 'JobState=[A-Z_]*' <<<"$info" | head -1)
  ec=$(grep -o ' ExitCode=[0-9:]*' <<<"$info" | head -1)
  echo "task $k: ${st:-unknown}${ec}"
  [ "$st" = JobState=COMPLETED ] || failed=1
  [ -s "$OUT/report.shard-$k-of-$SHARDS.jsonl" ] || { echo "no report of shard $k"; failed=1; }
done
for log in "$WORK"/logs/*; do
  echo "--- $(basename "$log")"
  cat "$log"
done
[ "$merge_rc" -eq 0 ] || { echo "merge job failed (sbatch --wait exit $merge_rc)"; failed=1; }
[ -s "$OUT/report.jsonl" ] || fail "no merged report"

# every input has exactly one row, and the rows are those files
(cd "$DATA" && find . -name '*.svg' -type f | sed 's|^\./||' | LC_ALL=C sort) >"$WORK/expected"
grep -o '"file":"[^"]*"' "$OUT/report.jsonl" | sed 's/^"file":"//; s/"$//' | LC_ALL=C sort >"$WORK/rows"
dups=$(uniq -d "$WORK/rows")
[ -z "$dups" ] || { echo "files with more than one row: $dups"; failed=1; }
if ! diff <(uniq "$WORK/rows") "$WORK/expected" >"$WORK/diff"; then
  echo "report rows differ from the files of $DATA (< report, > files):"
  cat "$WORK/diff"
  failed=1
fi
rows=$(wc -l <"$WORK/rows")
ok=$(grep -c '"status":"ok"' "$OUT/report.jsonl" || true)
meshes=$(find "$OUT" -name '*.msh' | wc -l)
echo "merged report: $rows rows for $(wc -l <"$WORK/expected") files, $ok ok, $meshes meshes"
# the page shows every file once in its gallery
cards=$(grep -o 'class="card [a-z]*" href="#f-[0-9]*" data-file="[^"]*"' "$OUT/report.html" 2>/dev/null |
  sed 's/.*data-file="//; s/"$//' | LC_ALL=C sort | uniq | wc -l || true)
echo "report page: $cards files in its gallery"
[ "$cards" -eq "$rows" ] || { echo "the page's gallery has $cards files, the report $rows"; failed=1; }
[ "$failed" -eq 0 ] || fail "slurm smoke test"
say "PASS: $SHARDS shards over $(wc -l <"$WORK/expected") files, one row each"
