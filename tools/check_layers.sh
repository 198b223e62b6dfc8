#!/usr/bin/env bash
# Which layer may include which. Each room (src/<room>/ and
# include/cncstream/<room>/) is listed with the rooms its files may include
# besides its own; a room missing from the table is an error, so a new layer
# is added by one line here. The apps (src/apps/) may include everything. The
# simulator (sim/) uses geometry, cam and G-code but never the protocol
# engines, transport, session or jobs (it must not depend on the streamer it
# tests); of the library's rooms only the session may use the simulator.
# Prints every include that breaks the table, with its file and line, and
# exits 1 if there is one.
set -u
root=${1:-$(dirname "$0")/..}
cd "$root" || exit 2

declare -A may_include=(
  [geometry]=""
  [image]="geometry"
  [cam]="geometry image"
  [gcode]="geometry image cam"
  [tooling]="geometry image cam protocol"
  [jobs]="geometry image cam gcode tooling"
  [protocol]="geometry image cam gcode"
  [transport]="geometry image cam gcode protocol"
  [session]="geometry image cam gcode protocol transport"
  [pendant]="geometry image cam gcode protocol transport session"
  [shop]="geometry image cam gcode jobs protocol transport session"
  [daemon]="geometry image cam gcode jobs protocol transport session pendant tooling shop"
  [gl]="geometry image cam"
  [viewer]="geometry image cam gcode gl"
)
# The machine session serves `PORT=sim` with the in-process simulator: it
# may include cncsim (the simulator never includes it back).
rooms_using_sim=" session "
sim_may_include="geometry image cam gcode"

bad=0
allowed() {  # allowed ROOM TARGET ALLOWED_ROOMS
  [[ $1 == "$2" || " $3 " == *" $2 "* ]]
}
check() {  # check FILE ROOM ALLOWED_ROOMS ALLOW_CNCSIM
  local file=$1 room=$2 rooms=$3 allow_sim=$4 line no target
  while IFS=: read -r no line; do
    if [[ $line =~ \#include\ \"cncstream/([a-z_]+)/ ]]; then
      target=${BASH_REMATCH[1]}
      if ! allowed "$room" "$target" "$rooms"; then
        echo "$file:$no: $room may not include cncstream/$target/ (it may include: ${rooms:-nothing else}): $line"; bad=1
      fi
    elif [[ $line =~ \#include\ \"cncsim/ && $allow_sim == no ]]; then
      echo "$file:$no: includes the simulator from a library layer: $line"; bad=1
    fi
  done < <(grep -n '^[[:space:]]*#include "' "$file")
}

for dir in src/* include/cncstream/*; do
  [[ -d $dir ]] || continue
  room=${dir##*/}
  [[ $room == apps ]] && continue
  if [[ ! -v may_include[$room] ]]; then
    echo "$dir: layer '$room' is not in tools/check_layers.sh's table of what each layer may include"; bad=1
    continue
  fi
  uses_sim=no
  [[ $rooms_using_sim == *" $room "* ]] && uses_sim=yes
  while IFS= read -r -d '' f; do check "$f" "$room" "${may_include[$room]}" "$uses_sim"; done \
    < <(find "$dir" -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0)
done
while IFS= read -r -d '' f; do check "$f" sim "$sim_may_include" yes; done \
  < <(find sim -type f \( -name '*.cpp' -o -name '*.hpp' \) -print0)

if (( bad )); then echo "layer order broken (see above)"; exit 1; fi
echo "layers: every include follows the table (geometry < image < cam < gcode < jobs; cam, protocol < tooling < jobs; gcode < protocol < transport < session < pendant; shop above session; daemon above jobs, session, pendant, tooling and shop; apps above all); sim/ stays below protocol"
