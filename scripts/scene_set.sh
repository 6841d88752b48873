#!/usr/bin/env bash
# The scene set of the hard dynamic cases (issue 15, docs/scenes.md): articulated people under a
# static, a translating and a fast-rotating camera, a person sitting down and getting up, large movers
# near a fast-rotating camera, and people composited into real TUM fr1/xyz frames. Every synthetic
# scene comes with its static twin (same seed and camera, no movers: NAME_twin); the augmented
# scene's twin is the real static sequence itself. Reproducible from the seeds below.
#
# usage: scripts/scene_set.sh OUT_DIR [FRAMES]   (FRAMES default 150)
# environment: FLOWFUSION (default build/apps/flowfusion), FLOWFUSION_SHARED_DATA (default ../shared/data)
set -euo pipefail

if [[ $# -lt 1 || $# -gt 2 ]]; then
  echo "usage: $0 OUT_DIR [FRAMES]" >&2
  exit 2
fi
out=$1
frames=${2:-150}
ff=${FLOWFUSION:-build/apps/flowfusion}
shared=${FLOWFUSION_SHARED_DATA:-../shared/data}
if [[ ! -x $ff ]]; then
  echo "$0: $ff is not an executable (build it or set FLOWFUSION)" >&2
  exit 2
fi
mkdir -p "$out"

# scene NAME SEED "MOVERS" CAMERA_OPTIONS...: the scene with MOVERS and its twin without them.
scene() {
  local name=$1 seed=$2 movers=$3
  shift 3
  # shellcheck disable=SC2086  # MOVERS is a list of options
  "$ff" synth "$out/$name" --seed "$seed" --frames "$frames" --objects 0 $movers "$@" --overwrite
  "$ff" synth "$out/${name}_twin" --seed "$seed" --frames "$frames" --objects 0 "$@" --overwrite
}

# People walking across a static camera's view; a chair pushed after 3 s still.
scene walking_static 1501 "--people 2 --pushed-objects 1" --camera-speed 0 --angular-speed 0
# People walking, the camera translating (hand-held sweep, slow rotation).
scene walking_xyz 1502 "--people 2" --camera-speed 0.3 --angular-speed 8
# People walking, the camera rotating fast about all axes (40 deg/s RMS), 20 ms motion blur.
scene walking_rpy 1503 "--people 2" --camera-motion rpy --angular-speed 40 --camera-speed 0.1 --exposure-ms 20
# One person walking to a seat, sitting down, getting up (the seat is in the twin too).
scene sitting 1504 "--people 1" --seats 1 --camera-speed 0.1 --angular-speed 3
# A large box close to the camera (20-40 % of the view) and a person, fast rotation, motion blur.
scene near_rpy 1505 "--near-objects 1 --people 1" --camera-motion rpy --angular-speed 40 --camera-speed 0.1 \
  --exposure-ms 20

# Real frames (issue 29), each twin the real sequence itself: people on fr1/xyz, one person on the
# fast-rotating, blurred fr1/rpy, a box 0.6-1.0 m in front of the camera on fr1/xyz.
fr1="$shared/tum/fr1_xyz_head300"
rpy="$shared/tum/fr1_rpy_head150"
if [[ -d $fr1 && -d $rpy ]]; then
  "$ff" augment "$fr1" "$out/fr1_people" --seed 1506 --objects 0 --people 2 --frames "0:$((frames - 1))" --overwrite
  "$ff" augment "$rpy" "$out/rpy_people" --seed 2901 --objects 0 --people 1 --overwrite
  "$ff" augment "$fr1" "$out/xyz_near" --seed 2902 --objects 1 --set min_distance=0.6 --set max_distance=1.0 \
    --frames "0:$((frames - 1))" --overwrite
else
  echo "$0: $fr1 or $rpy not found, skipping the augmented real scenes" >&2
fi
