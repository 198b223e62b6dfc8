#!/usr/bin/env bash
# The layers include downwards only: geometry < image < cam < gcode <
# protocol < transport < apps, and the simulator (sim/) uses geometry, cam and
# G-code but never the protocol engines or transport (it must not depend on
# the streamer it tests). Prints every include that breaks the order, with its
# file and line, and exits 1 if there is one.
set -u
root=${1:-$(dirname "$0")/..}
cd "$root" || exit 2
order=(geometry image cam gcode protocol transport)
rank() { local i; for i in "${!order[@]}"; do [[ ${order[$i]} == "$1" ]] && { echo "$i"; return; }; done; echo 99; }

bad=0
check() {  # check FILE MAX_RANK ALLOW_CNCSIM
  local file=$1 max=$2 allow_sim=$3 line no target
  while IFS=: read -r no line; do
    if [[ $line =~ \#include\ \"cncstream/([a-z_]+)/ ]]; then
      target=${BASH_REMATCH[1]}
      if (( $(rank "$target") > max )); then
        echo "$file:$no: includes cncstream/$target/ from a lower layer: $line"; bad=1
      fi
    elif [[ $line =~ \#include\ \"cncsim/ && $allow_sim == no ]]; then
      echo "$file:$no: includes the simulator from a library layer: $line"; bad=1
    fi
  done < <(grep -n '^[[:space:]]*#include "' "$file")
}

for layer in "${order[@]}"; do
  r=$(rank "$layer")
  while IFS= read -r -d '' f; do check "$f" "$r" no; done \
    < <(find "src/$layer" "include/cncstream/$layer" -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0 2>/dev/null)
done
while IFS= read -r -d '' f; do check "$f" "$(rank gcode)" yes; done \
  < <(find sim -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0)

if (( bad )); then echo "layer order broken (see above)"; exit 1; fi
echo "layers: every include follows geometry < image < cam < gcode < protocol < transport; sim/ stays below protocol"
