#!/usr/bin/env bash
# Long runs stay bounded: each shipped scene is simulated (`ponyhop sim`, physics only) for
# SECONDS of wall time; the peak resident memory (VmHWM) is read at 1 minute and at the end, and
# every value of the CSV written so far must be finite. Usage: scripts/soak.sh PONYHOP [SECONDS] [SCENE...]
# (`make soak`: every shipped scene, 600 s each, two at a time on two cores).
set -euo pipefail
PONYHOP=${1:?usage: soak.sh PONYHOP [SECONDS] [SCENE...]}
SECONDS_EACH=${2:-600}
shift $(( $# >= 2 ? 2 : 1 ))
SCENES=("$@")
if [ ${#SCENES[@]} -eq 0 ]; then SCENES=(assets/scenes/*.json); fi
PARALLEL=${SOAK_PARALLEL:-2}
WORK=$(mktemp -d /tmp/ponyhop-soak.XXXXXX)
trap 'rm -rf "$WORK"' EXIT

hwm_mb() { awk '/^VmHWM/ {printf "%.0f", $2 / 1024}' "/proc/$1/status" 2>/dev/null || echo "?"; }

soak_one() {
  local scene=$1 name csv partial pid start now hwm1="?" hwm_end="?" rc bad rows
  name=$(basename "$scene" .json)
  csv="$WORK/$name.csv"
  # As long as the wall-clock budget allows: the longest duration sim takes, stopped by SIGTERM at
  # SECONDS_EACH. The rows written so far (the temporary CSV.partial-PID, removed by sim when it
  # stops) are checked just before the signal.
  "$PONYHOP" sim "$scene" --duration 1000000 --csv "$csv" 2>"$WORK/$name.log" &
  pid=$!
  partial="$csv.partial-$pid"
  start=$(date +%s)
  while kill -0 "$pid" 2>/dev/null; do
    now=$(( $(date +%s) - start ))
    h=$(hwm_mb "$pid")
    [ "$h" != "?" ] && hwm_end=$h
    if [ "$now" -ge 60 ] && [ "$hwm1" = "?" ]; then hwm1=$h; fi
    if [ "$now" -ge "$SECONDS_EACH" ]; then
      rows=$(($(wc -l < "$partial") - 1))
      bad=$(tail -n +2 "$partial" | grep -ciE 'nan|inf' || true)
      kill -TERM "$pid"
      break
    fi
    sleep 2
  done
  rc=0; wait "$pid" || rc=$?
  now=$(( $(date +%s) - start ))
  # 143: stopped by our SIGTERM (the expected end); anything else is a failure.
  printf "soak: %-16s %8.1f s simulated in %4d s wall, exit %d, max RSS %s MB at 1 min, %s MB at the end, %d rows, %d with a non-finite value\n" \
    "$name" "$(awk -v r="${rows:-0}" 'BEGIN { print r / 1000 }')" "$now" "$rc" "$hwm1" "$hwm_end" "${rows:-0}" "${bad:-0}"
  [ "$rc" -eq 143 ] && [ "${bad:-1}" -eq 0 ]
}

echo "soak: ${#SCENES[@]} scenes, ${SECONDS_EACH} s each, $PARALLEL at a time ($(nproc) cores)"
fail=0
running=0
for s in "${SCENES[@]}"; do
  soak_one "$s" &
  running=$((running + 1))
  if [ "$running" -ge "$PARALLEL" ]; then
    wait -n || fail=1
    running=$((running - 1))
  fi
done
while [ "$running" -gt 0 ]; do
  wait -n || fail=1
  running=$((running - 1))
done
exit $fail
