#!/bin/sh
# bench/blur_check.py on one TUM sequence: the run as recorded, the same frames blurred over
# EXPOSURE_S by bench/blur_frames.py, then the comparison.
#
#   bench/blur_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY EXPOSURE_S OUT_DIR [LOW,HIGH MIN_BELOW_GATE_%]
# (the optional bounds: bench/blur_check.py's)
set -eu
if [ $# -ne 5 ] && [ $# -ne 7 ]; then
  echo "usage: bench/blur_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY EXPOSURE_S OUT_DIR [LOW,HIGH MIN_BELOW_GATE_%]" >&2
  exit 2
fi
here=$(dirname "$0")
rm -rf "$5/blurred" "$5/sharp.evaluation.csv" "$5/blurred.evaluation.csv"
mkdir -p "$5"
"$here/blur_frames.py" "$1" "$5/blurred" "$4"
for run in sharp blurred; do
  if [ $run = sharp ]; then frames=$1; else frames=$5/blurred; fi
  "$3" --source "tum:$frames" --config "$2" -q --groundtruth-allowance 0.0003,0.0015 \
    --evaluation "$5/$run.evaluation.csv" | grep "^summary:" | sed "s/^/$run /"
done
out=$5
shift 5
exec "$here/blur_check.py" "$out/sharp.evaluation.csv" "$out/blurred.evaluation.csv" "$@"
