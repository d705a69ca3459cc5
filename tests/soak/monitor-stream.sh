#!/usr/bin/env bash
# Soak test of `monitor --stream`: SECONDS of 100 kHz int16 noise (from /dev/urandom) piped
# in faster than real time; the monitor's resident memory (VmRSS, sampled every 0.1 s) must
# stay flat: after the first tenth of the run it grows by less than 1 MB.
#   tests/soak/monitor-stream.sh TROCHOMILL SECONDS
set -euo pipefail
bin=$1
seconds=$2
rate=100000
bytes=$(( seconds * rate * 2 ))
log=$(mktemp)
fifo=$(mktemp -u)
mkfifo "$fifo"
trap 'rm -f "$log" "$fifo"' EXIT
start=$(date +%s.%N)
# The monitor reads a FIFO (so $! is the monitor itself, not a pipeline's subshell).
"$bin" monitor --stream --rate "$rate" --format s16 < "$fifo" > "$log" &
pid=$!
head -c "$bytes" /dev/urandom > "$fifo" &
samples=()
while kill -0 "$pid" 2>/dev/null; do
  rss=$(sed -n 's/^VmRSS:[[:space:]]*\([0-9]*\).*/\1/p' "/proc/$pid/status" 2>/dev/null || true)
  [ -n "$rss" ] && samples+=("$rss")
  sleep 0.1
done
wait "$pid"
end=$(date +%s.%N)
lines=$(wc -l < "$log")
n=${#samples[@]}
if [ "$n" -lt 10 ]; then
  echo "soak: only $n memory samples: the run was too short to judge" >&2
  exit 1
fi
warm=$(( n / 10 ))
base=0
for (( i = 0; i <= warm; i++ )); do (( samples[i] > base )) && base=${samples[i]}; done
peak=0
for (( i = warm; i < n; i++ )); do (( samples[i] > peak )) && peak=${samples[i]}; done
growth=$(( peak - base ))
wall=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')
echo "soak: $seconds s of signal ($(( seconds * rate )) samples, $lines windows) in $wall s;" \
     "VmRSS $base kB after the first tenth, peak $peak kB after: growth $growth kB"
if [ "$growth" -ge 1024 ]; then
  echo "soak: memory grew by $growth kB (limit 1024 kB)" >&2
  exit 1
fi
