#!/usr/bin/env bash
# The ROS node tests' master: `start DIR` runs roscore on 127.0.0.1 at a free port, its logs and
# ROS_HOME under DIR, and writes DIR/master_uri once it answers; `stop DIR` ends it (SIGINT, then
# SIGKILL to its process group after 10 s). ctest runs them as the fixture's setup and cleanup.
set -euo pipefail
action=$1
dir=$2
case "$action" in
start)
  rm -rf "$dir"
  mkdir -p "$dir/home"
  port=$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_IP=127.0.0.1 ROS_HOME="$dir/home" ROS_LOG_DIR="$dir/home/log"
  setsid roscore -p "$port" >"$dir/roscore.log" 2>&1 </dev/null &
  echo $! >"$dir/pid"
  for _ in $(seq 1 150); do
    if rosparam list >/dev/null 2>&1; then
      echo "$ROS_MASTER_URI" >"$dir/master_uri"
      echo "roscore at $ROS_MASTER_URI"
      exit 0
    fi
    sleep 0.2
  done
  echo "roscore did not answer at $ROS_MASTER_URI within 30 s:" >&2
  cat "$dir/roscore.log" >&2
  kill -KILL -- "-$(cat "$dir/pid")" 2>/dev/null || true
  exit 1
  ;;
stop)
  [ -f "$dir/pid" ] || exit 0
  pid=$(cat "$dir/pid")
  kill -INT "$pid" 2>/dev/null || true
  for _ in $(seq 1 50); do
    kill -0 "$pid" 2>/dev/null || { rm -f "$dir/pid" "$dir/master_uri"; exit 0; }
    sleep 0.2
  done
  kill -KILL -- "-$pid" 2>/dev/null || true
  rm -f "$dir/pid" "$dir/master_uri"
  ;;
*)
  echo "usage: $0 start|stop DIR" >&2
  exit 2
  ;;
esac
