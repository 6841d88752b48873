#!/usr/bin/env bash
# Lists the functions (and lambdas) in src/ longer than a limit, longest first:
#   scripts/long-functions.sh [LIMIT_LINES (80)] [FOLDER (src)]
# Lengths are from universal-ctags (Debian: universal-ctags), counted from the line that opens the
# function to the line that closes it.
set -euo pipefail
limit=${1:-80}
folder=${2:-src}
command -v ctags >/dev/null || { echo "long-functions.sh: needs ctags (apt-get install universal-ctags)" >&2; exit 2; }
find "$folder" -name '*.cpp' -o -name '*.h' | sort |
  xargs ctags --fields=+ne --c++-kinds=f --kinds-c++=+l -o - 2>/dev/null |
  awk -F'\t' -v limit="$limit" '{
    line = ""; end = "";
    for (i = 4; i <= NF; i++) {
      if ($i ~ /^line:/) line = substr($i, 6);
      if ($i ~ /^end:/) end = substr($i, 5);
    }
    if (line != "" && end != "" && end - line + 1 > limit)
      printf "%d\t%s:%s\t%s\n", end - line + 1, $2, line, $1;
  }' | sort -rn
