#!/usr/bin/env bash
# The Snakemake workflow through a real Slurm against the same workflow run locally, on the tiny
# synthetic preset: starts a single-node cluster (tools/slurm_local.sh), runs both, checks that
# every view's depth map and the fused model are the same bytes, lists the Slurm jobs, and stops
# the cluster. Apart from the test command (it needs root and the Slurm packages:
# apt-get install slurmctld slurmd slurm-client munge, and for sacct slurmdbd mariadb-server).
# Run it as
#   nice -n 19 tools/slurm_workflow_check.sh [BUILD_DIR]      (default build)
set -euo pipefail
cd "$(dirname "$0")/.."
tools=$(realpath tools)
build=$(realpath "${1:-build}")
gcpstereo="$build/gcpstereo"
[ -x "$gcpstereo" ] || { echo "slurm_workflow_check: $gcpstereo not built" >&2; exit 1; }
command -v snakemake >/dev/null || { echo "slurm_workflow_check: snakemake not installed" >&2; exit 1; }
snakefile=$(realpath pipeline/workflow/Snakefile)
profile=$(realpath pipeline/workflow/slurm)

work=$(mktemp -d /tmp/gcpstereo-slurm-check-XXXXXX)
state="$work/slurm"
trap '"$tools/slurm_local.sh" stop "$state" >/dev/null 2>&1 || true' EXIT
"$tools/slurm_local.sh" start "$state"
export SLURM_CONF="$state/slurm.conf"
export USER=${USER:-$(id -un)}

"$gcpstereo" -q synth --preset tiny --seed 7 -o "$work/data" >/dev/null
cat > "$work/tiny.yaml" <<EOF
dataset: {format: strecha, path: $work/data, reference: all}
labels: {count: 48}
gcp: {sources: [lidar], lidar: {path: $work/data/gt/laser.ply}, downsample: 8}
optimizer: {tiles: [1, 1], refinement: parabola}
scene_mesh: {depth: 7}
eval: {scene: {max_samples: 100000}}
runtime: {log_level: warn}
EOF

cd "$work"
seconds() { python3 -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.1f}')" "$@"; }
start=$(date +%s.%N)
snakemake -s "$snakefile" --cores 2 --config config=tiny.yaml out=local gcpstereo="$gcpstereo" \
  > local.log 2>&1 || { tail -20 local.log; exit 1; }
local_s=$(seconds "$start" "$(date +%s.%N)")
start=$(date +%s.%N)
snakemake -s "$snakefile" --profile "$profile" --config config=tiny.yaml out=slurm \
  gcpstereo="$gcpstereo" > slurm.log 2>&1 || { tail -20 slurm.log; exit 1; }
slurm_s=$(seconds "$start" "$(date +%s.%N)")

status=0
for file in fused.ply mesh.ply mesh.obj effective_config.yaml $(cd local && ls views/*/depth.pfm); do
  if ! cmp -s "local/$file" "slurm/$file"; then echo "DIFFERENT: $file"; status=1; fi
done
echo "workflow with --cores 2: $local_s s; through Slurm: $slurm_s s"
if grep -q accounting_storage/slurmdbd "$SLURM_CONF"; then
  sleep 2  # slurmctld sends the last job's end to slurmdbd
  echo "Slurm jobs (sacct):"
  sacct -a -S now-1hour --format=JobID,JobName%20,State,AllocCPUS,ReqMem,MaxRSS,Elapsed,Start,End
else
echo "Slurm jobs (no accounting database, so scontrol rather than sacct):"
scontrol show job -o | python3 -c "$(cat <<'PY'
import re, sys
columns = ("JobId", "JobName", "JobState", "NumCPUs", "MinMemoryNode", "RunTime", "StartTime")
rows = [columns] + [tuple(dict(re.findall(r"(\w+)=(\S*)", line)).get(c, "") for c in columns)
                    for line in sys.stdin]
widths = [max(len(r[i]) for r in rows) for i in range(len(columns))]
for r in rows:
    print("  ".join(v.ljust(w) for v, w in zip(r, widths)))
PY
)"
fi
[ $status -eq 0 ] && echo "slurm_workflow_check: the Slurm run's views and model are the local run's bytes"
exit $status
