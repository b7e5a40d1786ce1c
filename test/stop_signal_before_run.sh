#!/usr/bin/env bash
# SIGTERM before the run (here: the source's index file is a FIFO nobody writes, so opening
# the sequence blocks for ever, as a vendor driver or reader that does not return would) must
# end the process at once with 128 + 15, not wait for a run that never starts.
# usage: stop_signal_before_run.sh SCRATCH_DIR [EMULATOR...] EXE
set -u
dir=$1
shift
rm -rf "$dir" && mkdir -p "$dir/seq"
mkfifo "$dir/seq/rgb.txt"
"$@" --source "tum:$dir/seq" -q > "$dir/out.txt" 2>&1 &
pid=$!
sleep 1
kill -TERM "$pid"
for _ in $(seq 100); do
  kill -0 "$pid" 2>/dev/null || break
  sleep 0.1
done
if kill -0 "$pid" 2>/dev/null; then
  kill -KILL "$pid"
  echo "still running 10 s after SIGTERM"
  exit 1
fi
wait "$pid"
rc=$?
if [ "$rc" -ne 143 ]; then
  echo "exit status $rc, expected 143:"
  cat "$dir/out.txt"
  exit 1
fi
echo "ended by SIGTERM before the run: status $rc"
