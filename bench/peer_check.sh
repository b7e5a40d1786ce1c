#!/bin/sh
# The three-cornered hat of bench/peer_check.py on one TUM sequence: our run (its --log and
# --evaluation files), the peer's estimate of the same pairs, then the comparison.
#
#   bench/peer_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY PEER_ODOMETRY OUT_PREFIX
set -eu
if [ $# -ne 5 ]; then
  echo "usage: bench/peer_check.sh TUM_DIR CONFIG.yaml RGBD_ODOMETRY PEER_ODOMETRY OUT_PREFIX" >&2
  exit 2
fi
rm -f "$5.log.csv" "$5.evaluation.csv" "$5.peer.csv"  # the program would keep an old log as .1
"$3" --source "tum:$1" --config "$2" -q --groundtruth-allowance 0.0003,0.0015 \
  --log "$5.log.csv" --evaluation "$5.evaluation.csv" >/dev/null
"$4" "$1" "$2" >"$5.peer.csv"
exec "$(dirname "$0")/peer_check.py" "$5.log.csv" "$5.evaluation.csv" "$5.peer.csv"
