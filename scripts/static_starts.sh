#!/usr/bin/env bash
# False marks at many starts of a static sequence (docs/tuning.md#start_max_black_share): a run
# starts without a map or scores, so its first frames are where a static scene is most often marked
# dynamic, and one run shows one start. This runs FRAMES frames from every EVERY-th frame up to LAST
# and prints, per start, the mean share marked, the largest share of a frame and the frames above
# 5 % (`flowfusion eval static`), then the starts with a frame above 5 % and the mean over all.
#
# usage: scripts/static_starts.sh SEQUENCE OUT_DIR LAST [EVERY [FRAMES]] [-- RUN_OPTIONS...]
#   LAST: the last start frame (a start needs FRAMES associated frames after it)
#   e.g.: scripts/static_starts.sh ../shared/data/tum/fr1_xyz_head300 /tmp/starts 270
#         scripts/static_starts.sh ../shared/data/tum/fr1_rpy_head150 /tmp/starts 130 10 16 -- --set consensus.start_max_black_share=1
# environment: FLOWFUSION (default build/apps/flowfusion)
set -euo pipefail

usage() {
  echo "usage: $0 SEQUENCE OUT_DIR LAST [EVERY [FRAMES]] [-- RUN_OPTIONS...]" >&2
  exit 2
}
[[ $# -ge 3 ]] || usage
seq=$1 out=$2 last=$3
shift 3
every=10 frames=16
if [[ $# -gt 0 && $1 != -- ]]; then every=$1; shift; fi
if [[ $# -gt 0 && $1 != -- ]]; then frames=$1; shift; fi
if [[ $# -gt 0 ]]; then
  [[ $1 == -- ]] || usage
  shift
fi
for n in "$last" "$every" "$frames"; do
  [[ $n =~ ^[0-9]+$ ]] || { echo "$0: LAST, EVERY and FRAMES must be whole numbers, got '$n'" >&2; exit 2; }
done
(( every > 0 && frames > 1 )) || { echo "$0: EVERY must be at least 1 and FRAMES at least 2" >&2; exit 2; }
ff=${FLOWFUSION:-build/apps/flowfusion}
[[ -x $ff ]] || { echo "$0: $ff is not an executable (build it or set FLOWFUSION)" >&2; exit 2; }
[[ -d $seq ]] || { echo "$0: sequence folder $seq not found" >&2; exit 2; }
mkdir -p "$out"

above=() sum=0 count=0
for ((first = 0; first <= last; first += every)); do
  run="$out/start_$first"
  "$ff" run "$seq" --frames "$first:$((first + frames - 1))" --out "$run" --overwrite --quiet --no-map "$@"
  read -r mean max frames_above < <("$ff" eval static "$run/masks" |
    awk '/^mean_marked/ {m = $2} /^max_marked/ {x = $2} /^frames_above/ {a = $2} END {print m, x, a}')
  printf 'start %4d  mean marked %6.2f %%  largest %6.2f %%  frames above 5 %%: %s\n' \
    "$first" "$(awk -v m="$mean" 'BEGIN {print 100 * m}')" "$(awk -v x="$max" 'BEGIN {print 100 * x}')" "$frames_above"
  (( frames_above > 0 )) && above+=("$first")
  sum=$(awk -v s="$sum" -v m="$mean" 'BEGIN {print s + m}')
  count=$((count + 1))
done
printf 'starts %d, with a frame above 5 %%: %d (%s); mean marked over all starts %.2f %%\n' \
  "$count" "${#above[@]}" "${above[*]:-none}" "$(awk -v s="$sum" -v n="$count" 'BEGIN {print 100 * s / n}')"
