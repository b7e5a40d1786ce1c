#!/bin/sh
# The three-cornered hat of bench/peer_check.py on one TUM sequence: our run (its --log and
# --evaluation files), the peer's estimate of the same pairs, then the comparison.
#
#   bench/peer_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY PEER_ODOMETRY OUT_PREFIX [OPTION...]
#
# OPTIONs go to our run (e.g. --imu FILE; an imu.txt in TUM_DIR is read without one): a run
# restamped against a gyro is joined to the peer's pairs frame by frame.
set -eu
if [ $# -lt 5 ]; then
  echo "usage: bench/peer_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY PEER_ODOMETRY OUT_PREFIX [OPTION...]" >&2
  exit 2
fi
dir=$1 config=$2 ours=$3 peer=$4 out=$5
shift 5
rm -f "$out.log.csv" "$out.evaluation.csv" "$out.peer.csv"  # the program would keep an old log as .1
"$ours" --source "tum:$dir" --config "$config" -q --groundtruth-allowance 0.0003,0.0015 \
  --log "$out.log.csv" --evaluation "$out.evaluation.csv" "$@" >/dev/null
"$peer" "$dir" "$config" >"$out.peer.csv"
exec "$(dirname "$0")/peer_check.py" "$out.log.csv" "$out.evaluation.csv" "$out.peer.csv"
