#!/usr/bin/env bash
# A single-node Slurm cluster on this machine (Debian 12: slurmctld, slurmd, slurm-client, munge),
# to try the Snakemake workflow's Slurm profile (pipeline/workflow/slurm/) on a real Slurm rather
# than a mock. Everything (configuration, munge key and socket, spool, logs) lives in STATE_DIR;
# nothing under /etc is touched and no system service is started.
#
#   tools/slurm_local.sh start [STATE_DIR]   # default /tmp/gcpstereo-slurm; prints what to export
#   tools/slurm_local.sh stop  [STATE_DIR]
#
# Then, with SLURM_CONF exported as printed:
#   snakemake -s pipeline/workflow/Snakefile --profile pipeline/workflow/slurm \
#       --config config=CONFIG.yaml out=OUTDIR
#
# As root (the daemons' SlurmUser). slurmd runs at the niceness this script is started with, and
# its jobs inherit it (PropagatePrioProcess=0): `nice -n 19 tools/slurm_local.sh start` keeps them
# in the background of a machine doing other work. With slurmdbd and mariadb-server installed it
# also starts a MariaDB server (TCP 127.0.0.1:3307, data in STATE_DIR) and slurmdbd, so that
# `sacct` lists the jobs; without them there is no accounting and `squeue`, `scontrol show job`
# (jobs stay listed MinJobAge = 1 h after they end) and slurmctld.log show the jobs.
set -euo pipefail

command=${1:-}
state=${2:-/tmp/gcpstereo-slurm}

die() { echo "slurm_local: $*" >&2; exit 1; }

stop() {
  for daemon in slurmd slurmctld slurmdbd mariadbd munged; do
    local pidfile="$state/run/$daemon.pid"
    if [ -f "$pidfile" ]; then
      local pid
      pid=$(cat "$pidfile")
      if kill -0 "$pid" 2>/dev/null; then
        kill "$pid"
        for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      fi
      rm -f "$pidfile"
    fi
  done
  echo "slurm_local: stopped ($state)"
}

# MariaDB (its own data folder and port) and slurmdbd on it; slurmdbd reads slurmdbd.conf beside
# slurm.conf ($SLURM_CONF).
start_accounting() {
  local password=gcpstereo-local
  if [ ! -d "$state/db/mysql" ]; then
    mariadb-install-db --user=root --datadir="$state/db" --auth-root-authentication-method=normal \
      --skip-test-db > "$state/log/mariadb-install.log" 2>&1 ||
      die "mariadb-install-db failed (see $state/log/mariadb-install.log)"
  fi
  mariadbd --user=root --datadir="$state/db" --socket="$state/run/mariadb.sock" \
    --pid-file="$state/run/mariadbd.pid" --port=3307 --bind-address=127.0.0.1 \
    --log-error="$state/log/mariadb.log" < /dev/null > /dev/null 2>&1 &
  for _ in $(seq 100); do
    mariadb --socket="$state/run/mariadb.sock" -u root -e 'SELECT 1' >/dev/null 2>&1 && break
    sleep 0.2
  done
  mariadb --socket="$state/run/mariadb.sock" -u root -e "
    CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY '$password';
    GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';" ||
    die "MariaDB did not start (see $state/log/mariadb.log)"
  cat > "$state/slurmdbd.conf" <<EOF
AuthType=auth/munge
AuthInfo=socket=$state/munge/munge.socket
DbdHost=localhost
DbdPort=6819
SlurmUser=root
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=3307
StorageUser=slurm
StoragePass=$password
StorageLoc=slurm_acct_db
PidFile=$state/run/slurmdbd.pid
LogFile=$state/log/slurmdbd.log
EOF
  chmod 600 "$state/slurmdbd.conf"
  SLURM_CONF="$state/slurm.conf" slurmdbd
  for _ in $(seq 100); do
    (echo > /dev/tcp/127.0.0.1/6819) 2>/dev/null && return 0
    sleep 0.2
  done
  die "slurmdbd did not start (see $state/log/slurmdbd.log)"
}

start() {
  [ "$(id -u)" -eq 0 ] || die "run as root (the daemons' SlurmUser is root)"
  for tool in munged slurmctld slurmd sinfo sbatch; do
    command -v "$tool" >/dev/null ||
      die "$tool not found: apt-get install slurmctld slurmd slurm-client munge"
  done
  [ -f "$state/run/slurmctld.pid" ] && kill -0 "$(cat "$state/run/slurmctld.pid")" 2>/dev/null &&
    die "already running in $state (tools/slurm_local.sh stop $state first)"

  mkdir -p "$state"/{run,log,ctld,spool,munge}
  chmod 700 "$state/munge"
  local host cpus mem_mb
  host=$(hostname -s)
  cpus=$(nproc)
  # What the node offers jobs: all but 1 GB of the memory.
  mem_mb=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 - 1024 ))

  if [ ! -f "$state/munge/munge.key" ]; then
    dd if=/dev/urandom of="$state/munge/munge.key" bs=1024 count=1 status=none
    chmod 400 "$state/munge/munge.key"
  fi
  munged --force --key-file="$state/munge/munge.key" --socket="$state/munge/munge.socket" \
    --pid-file="$state/run/munged.pid" --log-file="$state/log/munged.log" \
    --seed-file="$state/munge/munge.seed"

  local accounting="AccountingStorageType=accounting_storage/none"
  if command -v slurmdbd >/dev/null && command -v mariadbd >/dev/null; then
    start_accounting
    accounting="AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
AccountingStoragePort=6819
AccountingStoragePass=$state/munge/munge.socket"
  fi

  cat > "$state/slurm.conf" <<EOF
# Written by tools/slurm_local.sh: one node, this machine.
ClusterName=gcpstereo-local
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$state/munge/munge.socket
CredType=cred/munge
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$state/ctld
SlurmdSpoolDir=$state/spool
SlurmctldPidFile=$state/run/slurmctld.pid
SlurmdPidFile=$state/run/slurmd.pid
SlurmctldLogFile=$state/log/slurmctld.log
SlurmdLogFile=$state/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU_Memory
JobAcctGatherType=jobacct_gather/linux
$accounting
JobCompType=jobcomp/none
PropagatePrioProcess=0
ReturnToService=2
MinJobAge=3600
SlurmdTimeout=60
NodeName=$host NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=local Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
  export SLURM_CONF="$state/slurm.conf"
  slurmctld -f "$SLURM_CONF"
  slurmd -f "$SLURM_CONF"
  for _ in $(seq 100); do
    if sinfo -h -N -o %t 2>/dev/null | grep -qx idle; then
      echo "slurm_local: node $host up ($cpus CPUs, $mem_mb MB) in partition local; state in $state"
      echo "export SLURM_CONF=$SLURM_CONF"
      return 0
    fi
    sleep 0.2
  done
  sinfo -N -l >&2 || true
  tail -5 "$state/log/slurmctld.log" "$state/log/slurmd.log" >&2 || true
  die "the node did not come up within 20 s (logs in $state/log)"
}

case "$command" in
  start) start ;;
  stop) stop ;;
  *) die "usage: tools/slurm_local.sh start|stop [STATE_DIR]" ;;
esac
