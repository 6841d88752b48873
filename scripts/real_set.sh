#!/usr/bin/env bash
# The real scene set of issue 29 (docs/scenes.md, "Judging a change on real frames"): movers
# composited into the real TUM frames of ../shared/data/tum by `augment` (generator version 4), each
# with the real static sequence as its twin, and the two static sequences themselves. The first seven
# are the scenes the pipeline was tuned on, the last four were made only to check it. Reproducible
# from the seeds below.
#
# usage: scripts/real_set.sh OUT_DIR
#   then: flowfusion bench OUT_DIR/* SHARED/tum/fr1_rpy_head150 SHARED/tum/fr1_xyz_head300 --no-reference
#   (the lines under bench's table are the set's means: mIoU and precision of the augmented scenes,
#   the marked share of the static ones)
# environment: FLOWFUSION (default build/apps/flowfusion), FLOWFUSION_SHARED_DATA (default ../shared/data)
# and AUGMENT_OPTIONS, added to every scene's augment (e.g. "--set band_depth=drawn": the movers with
# their depth in the sensor's band, generator version 3's scenes; docs/scenes.md)
set -euo pipefail

if [[ $# -ne 1 ]]; then
  echo "usage: $0 OUT_DIR" >&2
  exit 2
fi
out=$1
ff=${FLOWFUSION:-build/apps/flowfusion}
shared=${FLOWFUSION_SHARED_DATA:-../shared/data}
xyz="$shared/tum/fr1_xyz_head300"
rpy="$shared/tum/fr1_rpy_head150"
if [[ ! -x $ff ]]; then
  echo "$0: $ff is not an executable (build it or set FLOWFUSION)" >&2
  exit 2
fi
if [[ ! -d $xyz || ! -d $rpy ]]; then
  echo "$0: $xyz or $rpy not found (set FLOWFUSION_SHARED_DATA to the folder holding tum/)" >&2
  exit 2
fi
mkdir -p "$out"

# scene NAME STATIC SEED AUGMENT_OPTIONS...
scene() {
  local name=$1 static=$2 seed=$3
  shift 3
  # shellcheck disable=SC2086  # AUGMENT_OPTIONS is a list of words
  "$ff" augment "$static" "$out/$name" --seed "$seed" "$@" ${AUGMENT_OPTIONS:-} --overwrite
}

near=(--set min_distance=0.6 --set max_distance=1.0)  # boxes 0.6-1.0 m in front of the camera
scene fr1_people "$xyz" 1506 --objects 0 --people 2 --frames 0:149
scene rpy_people "$rpy" 2901 --objects 0 --people 1
scene xyz_near "$xyz" 2902 --objects 1 "${near[@]}" --frames 0:149
scene h_xyz_people "$xyz" 77 --objects 0 --people 1
scene h_rpy_near "$rpy" 78 --objects 2 "${near[@]}"
scene h_rpy_people2 "$rpy" 79 --objects 0 --people 2
scene h_xyz_objects "$xyz" 80 --objects 2 --frames 100:293
# Made only to check the seven above.
scene n_xyz_people2 "$xyz" 91 --objects 0 --people 2
scene n_rpy_people "$rpy" 92 --objects 0 --people 1
scene n_rpy_mixed "$rpy" 94 --objects 1 --people 1
scene n_xyz_objects "$xyz" 95 --objects 2
