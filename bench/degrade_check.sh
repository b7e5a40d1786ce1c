#!/bin/sh
# Does the depth noise the program learns from the data follow a known change of the sensor?
# One TUM sequence as recorded, then with depth noise of the law NOISE Z^2 added
# (bench/degrade_depth.py): the second reading must be the first and NOISE added in
# quadrature, within TOLERANCE_%, and the covariance must still hold (pair NEES mean in
# [3, 9], where 6 is consistent).
#
#   bench/degrade_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY NOISE OUT_DIR TOLERANCE_%
set -eu
if [ $# -ne 6 ]; then
  echo "usage: bench/degrade_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY NOISE OUT_DIR TOLERANCE_%" >&2
  exit 2
fi
here=$(dirname "$0")
out=$5
rm -rf "$5/degraded"
mkdir -p "$5"
"$here/degrade_depth.py" "$1" "$5/degraded" --noise "$4"
for run in recorded degraded; do
  if [ $run = recorded ]; then frames=$1; else frames=$5/degraded; fi
  "$3" --source "tum:$frames" --config "$2" -q --groundtruth-allowance 0.0003,0.0015 >"$5/$run.summary"
  grep -E "learnt from the data|NEES per pair" "$5/$run.summary" | sed "s/^ */$run: /"
done
coeff() { sed -n 's/.*depth noise \([0-9.]*\)e-3 Z^2.*/\1/p' "$out/$1.summary"; }
nees() { sed -n 's/.*NEES per pair ([0-9]*): mean \([0-9.]*\).*/\1/p' "$out/$1.summary"; }
awk -v a="$(coeff recorded)" -v b="$(coeff degraded)" -v n="$4" -v tol="$6" -v nees="$(nees degraded)" 'BEGIN {
  if (a == "" || b == "" || nees == "") { print "no learnt depth noise or NEES in a summary"; exit 1 }
  expected = sqrt(a * a + (n * 1e3) ^ 2)
  printf "depth noise read %.3fe-3 as recorded, %.3fe-3 degraded; expected %.3fe-3 (%+.1f %%)\n", a, b, expected, 100 * (b / expected - 1)
  if (b < expected * (1 - tol / 100) || b > expected * (1 + tol / 100)) { print "the depth noise is not read back"; exit 1 }
  if (nees < 3 || nees > 9) { printf "pair NEES %s degraded: the covariance does not hold\n", nees; exit 1 }
  print "the depth noise is read back and the covariance holds"
}'
