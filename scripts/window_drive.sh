#!/bin/sh
# Drives `ponyhop run` in an X display the way a person tunes a scene: it plays, Space pauses it,
# it stands still, a drag in the scene view orbits the camera, it stands still again. The window
# writes which quality it showed on every frame (--quality-log) and prints its frames per second
# while moving (draft) and still (final) when it exits.
#
#   xvfb-run -a -s '-screen 0 1280x720x24' sh scripts/window_drive.sh build/ponyhop \
#       assets/scenes/ponytail.json /tmp/quality.log [FRAMES]
#
# PLAY, STILL and DRAG (frames played before the pause, frames still before the drag, mouse moves
# of the drag, one frame each) set the phases: defaults 6, 8, 6 (the window test); FRAMES (default
# 90) must cover them. SHOT=FILE.png writes the last frame's screenshot; IDLE_WAIT=SECONDS sets
# `run --idle-wait` (how long a frame after one that changed nothing waits for an event; unset:
# run's default, and no option passed, so older binaries take the same command). Needs xdotool.
# tests/app/window_test.cpp runs it. The window prints the draft and final frame rates, how many
# still frames were rendered or re-presented, and whether each first still frame was final.
set -u
EXE=$1
SCENE=$2
QLOG=$3
FRAMES=${4:-90}
PLAY=${PLAY:-6}
STILL=${STILL:-8}
DRAG=${DRAG:-6}
rm -f "$QLOG"
"$EXE" run "$SCENE" --size 1280x720 --no-vsync --frames "$FRAMES" --quality-log "$QLOG" ${SHOT:+--screenshot "$SHOT"} \
  ${IDLE_WAIT:+--idle-wait "$IDLE_WAIT"} &
pid=$!
lines() { if [ -f "$QLOG" ]; then wc -l < "$QLOG"; else echo 0; fi; }
# Waits until the window has shown $1 more frames (or gave up after 60 s, or exited).
waitfor() {
  n=$(( $(lines) + $1 )); i=0
  while [ "$(lines)" -lt "$n" ] && kill -0 $pid 2> /dev/null && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
}
waitfor "$PLAY"                             # the scene plays
xdotool mousemove 440 360                   # no window manager: focus the window, then pause
win=$(xdotool search --pid $pid 2> /dev/null | head -1)
[ -n "$win" ] && xdotool windowfocus --sync "$win" 2> /dev/null
xdotool key space
waitfor "$STILL"                            # still
xdotool mousedown 1                         # orbit: drag in the scene view
k=0
while [ $k -lt "$DRAG" ]; do xdotool mousemove_relative -- 12 3; waitfor 1; k=$((k + 1)); done
xdotool mouseup 1
wait $pid                                   # still again until the last frame
