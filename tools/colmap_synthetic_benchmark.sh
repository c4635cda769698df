#!/usr/bin/env bash
# Builds a COLMAP model of the synthetic fountain and measures gcpstereo on it (issue 21,
# "SfM GCPs on ground truth" and "Alignment"; README, "COLMAP models").
#
# Usage: tools/colmap_synthetic_benchmark.sh SYNTH_DIR OUT_DIR [GCPSTEREO]
#   SYNTH_DIR  the synthetic fountain (gcpstereo synth --preset fountain -o SYNTH_DIR): images/,
#              cameras/*.png.camera, gt/{NNNN.depth.pfm, NNNN.sigma.pfm, laser.ply}
#   OUT_DIR    created; holds the COLMAP model (OUT_DIR/colmap: database, sparse/0, and the
#              undistorted workspace OUT_DIR/colmap/workspace), the gcpstereo runs of view 0005
#              (OUT_DIR/run-*: GCP sources sfm, lidar, both, none with dataset.align: scan; sfm
#              and lidar with align: centres), their scores (OUT_DIR/checks) and the table
#              OUT_DIR/summary.md
#   GCPSTEREO  the gcpstereo binary (default: build/gcpstereo)
#
# Needs Debian's colmap package (3.8; CPU: --SiftExtraction.use_gpu 0 --SiftMatching.use_gpu 0,
# 2 threads), the way ../shared/data/colmap/fountain-P11 was made: one shared PINHOLE camera,
# exhaustive_matcher, mapper, image_undistorter --output_type COLMAP. colmap is not a build or
# test dependency of gcpstereo: it is used here only. A finished COLMAP stage is reused when the
# script runs again on the same OUT_DIR. Set NICE="nice -n 19" to run everything niced.
set -euo pipefail

usage() { sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
[[ $# -ge 2 && $# -le 3 ]] || usage
synth=$(cd "$1" && pwd)
out=$2
gcpstereo=${3:-build/gcpstereo}
here=$(cd "$(dirname "$0")" && pwd)
nice_cmd=${NICE:-}
threads=2

if ! command -v colmap >/dev/null 2>&1; then
  echo "error: colmap not found on PATH; this benchmark needs it (Debian: apt-get install colmap)." >&2
  exit 1
fi
for tool in /usr/bin/time python3; do
  command -v "$tool" >/dev/null 2>&1 || { echo "error: $tool not found (Debian: time, python3)" >&2; exit 1; }
done
[[ -x $gcpstereo ]] || { echo "error: gcpstereo binary '$gcpstereo' not found or not executable" >&2; exit 1; }
for f in images cameras gt/laser.ply gt/0005.depth.pfm gt/0005.sigma.pfm; do
  [[ -e $synth/$f ]] || { echo "error: $synth/$f missing: not a synthetic fountain folder" >&2; exit 1; }
done
mkdir -p "$out/colmap"
out=$(cd "$out" && pwd)
gcpstereo=$(cd "$(dirname "$gcpstereo")" && pwd)/$(basename "$gcpstereo")
col=$out/colmap
ws=$col/workspace

# --- 1. The COLMAP model (as ../shared/data/colmap/fountain-P11/README.md, without model_aligner:
#        the model stays in COLMAP's own frame and scale, and gcpstereo aligns it to the scan).
if [[ ! -e $ws/sparse/images.bin ]]; then
  rm -rf "$col/database.db" "$col/sparse" "$ws"
  mkdir -p "$col/sparse"
  log=$col/colmap.log
  : >"$log"
  step() { echo "== colmap $1" | tee -a "$log"; /usr/bin/time -v $nice_cmd colmap "$@" >>"$log" 2>&1 \
             || { echo "error: colmap $1 failed, see $log" >&2; exit 1; }; }
  step feature_extractor --database_path "$col/database.db" --image_path "$synth/images" \
    --ImageReader.single_camera 1 --ImageReader.camera_model PINHOLE \
    --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads $threads
  step exhaustive_matcher --database_path "$col/database.db" \
    --SiftMatching.use_gpu 0 --SiftMatching.num_threads $threads
  step mapper --database_path "$col/database.db" --image_path "$synth/images" \
    --output_path "$col/sparse" --Mapper.num_threads $threads
  [[ -e $col/sparse/0/images.bin ]] || { echo "error: colmap mapper wrote no model, see $log" >&2; exit 1; }
  if [[ -e $col/sparse/1 ]]; then
    echo "warning: colmap mapper made several models; using sparse/0" | tee -a "$log" >&2
  fi
  step model_analyzer --path "$col/sparse/0"
  step image_undistorter --image_path "$synth/images" --input_path "$col/sparse/0" \
    --output_path "$ws" --output_type COLMAP
fi

# --- 2. gcpstereo on view 0005 at configs/synthetic_fountain.yaml's per-view setting, moved to the
#        COLMAP workspace: the same neighbours, labels, GCP downsampling, propagation and tiles.
#        The model aligned to the laser scan (dataset.align: scan), which the scan GCPs and the
#        scoring share, with each GCP source set; for contrast, [sfm] and [lidar] with the model
#        aligned to the true camera centres instead (dataset.align: centres, cameras/*.camera
#        line 8). One run after the other; a finished run (report.json) is kept.
config=$here/../configs/synthetic_fountain.yaml
centres=$out/true_centres.txt
for f in "$synth"/cameras/*.camera; do
  echo "$(basename "$f" .camera) $(sed -n 8p "$f")"
done >"$centres"
common=(--set dataset.format=colmap --set "dataset.path=$ws" --set dataset.reference=0005.png
        --set "dataset.neighbors=[0002.png,0003.png,0004.png,0006.png,0007.png,0008.png]"
        --set "gcp.lidar.path=$synth/gt/laser.ply")
# name  gcp.sources  dataset.align
runs=("sfm [sfm] scan" "lidar [lidar] scan" "sfm+lidar [sfm,lidar] scan" "none [] scan"
      "centres-sfm [sfm] centres" "centres-lidar [lidar] centres")
mkdir -p "$out/checks"
for spec in "${runs[@]}"; do
  read -r name sources align <<<"$spec"
  run=$out/run-$name
  extra=(--set "dataset.align=$align")
  [[ $align == centres ]] && extra+=(--set "dataset.align_centres=$centres")
  if [[ ! -e $run/report.json ]]; then
    echo "== gcpstereo run, gcp.sources=$sources, dataset.align=$align -> $run"
    /usr/bin/time -v -o "$out/checks/$name.time" $nice_cmd "$gcpstereo" run "$config" -o "$run" \
      "${common[@]}" "${extra[@]}" --set "gcp.sources=$sources" >"$out/checks/$name.log" 2>&1 \
      || { echo "error: gcpstereo run $name failed, see $out/checks/$name.log" >&2; exit 1; }
  fi
done
for spec in "${runs[@]}"; do
  read -r name _ _ <<<"$spec"
  run=$out/run-$name
  # Scored as gcpstereo eval does (pixel by pixel) and in the true camera's frame (the check).
  $nice_cmd "$gcpstereo" eval --depth "$run/depth.pfm" --gt-depth "$synth/gt/0005.depth.pfm" \
    --gt-sigma "$synth/gt/0005.sigma.pfm" --report "$out/checks/$name.eval.json" >/dev/null
  if [[ -e $run/propagated_depth.pfm ]]; then
    $nice_cmd "$gcpstereo" eval --depth "$run/propagated_depth.pfm" \
      --gt-depth "$synth/gt/0005.depth.pfm" --gt-sigma "$synth/gt/0005.sigma.pfm" \
      --report "$out/checks/$name.propagated.eval.json" >/dev/null
  fi
  $nice_cmd python3 "$here/colmap_synthetic_check.py" dense "$run" "$synth" 0005 >"$out/checks/$name.dense.json"
  $nice_cmd python3 "$here/colmap_synthetic_check.py" gcps "$run" "$synth" 0005 >"$out/checks/$name.gcps.json"
done
$nice_cmd python3 "$here/colmap_synthetic_check.py" align "$out/run-sfm" "$synth" >"$out/checks/align.json"
$nice_cmd python3 "$here/colmap_synthetic_check.py" align "$out/run-centres-sfm" "$synth" >"$out/checks/align-centres.json"
python3 "$here/colmap_synthetic_check.py" summary "$out" | tee "$out/summary.md"
