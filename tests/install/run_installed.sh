#!/usr/bin/env bash
# Installs the build into a temporary prefix, moves the prefix elsewhere and
# runs the installed cncstream there, proving the programs need nothing from
# the source or build tree:
#   - the binaries hold no path to the source tree's firmware-profiles;
#   - the moved prefix (installed paths are relative to bin/) machines the
#     plaque from a copy of the example, working folder and state in a temp dir;
#   - with the moved prefix's profiles removed the program fails, naming the
#     places it looked, none of them in the source tree (there is no hidden
#     fallback); CNCSTREAM_PROFILES then points it at a profile folder again.
# Usage: run_installed.sh BUILD_DIR SOURCE_DIR
set -euo pipefail
build=$(realpath "$1")
source_dir=$(realpath "$2")

tmp=$(mktemp -d "${TMPDIR:-/tmp}/cncstream_install.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$build" --prefix "$tmp/prefix" >"$tmp/install.log" || { cat "$tmp/install.log"; fail "cmake --install"; }
for f in bin/cncstream bin/cncsim share/cncstream/firmware-profiles/grbl-1.1.toml \
         share/doc/cncstream/README.md share/doc/cncstream/examples/plaque.stl; do
  [[ -e $tmp/prefix/$f ]] || fail "not installed: $f"
done

# Nothing compiled in points at the source tree's profiles.
for exe in cncstream cncsim; do
  if strings "$tmp/prefix/bin/$exe" | grep -qF "$source_dir/firmware-profiles"; then
    fail "bin/$exe holds the source path $source_dir/firmware-profiles"
  fi
done

# A moved install still finds its own profiles (relative to bin/, not the prefix).
mv "$tmp/prefix" "$tmp/moved"
mkdir -p "$tmp/work"
cp "$tmp/moved/share/doc/cncstream/examples/plaque.stl" "$tmp/work/plaque.stl"
cd "$tmp/work"
run() {  # run ARGS...: the installed cncstream, clean environment, no terminal
  env -u CNCSTREAM_PROFILES XDG_STATE_HOME="$tmp/state" HOME="$tmp/home" "$@" </dev/null
}

run "$tmp/moved/bin/cncsim" --help >"$tmp/cncsim.log" 2>&1 || { cat "$tmp/cncsim.log"; fail "installed cncsim --help"; }

if ! run "$tmp/moved/bin/cncstream" plaque.stl sim --tool ball:3.175 --rough flat:6 --stepover 2 --tolerance 0.02 --sim-speed max \
     --yes --journal "$tmp/journal.sqlite" >"$tmp/job.log" 2>&1; then
  cat "$tmp/job.log"; fail "the installed cncstream did not machine the plaque"
fi
[[ -s $tmp/journal.sqlite ]] || fail "no journal written"

# Without its profiles the moved install must fail, not find the source tree's.
printf 'G21 G90\nG0 X1 Y1\n' >tiny.nc
rm -rf "$tmp/moved/share/cncstream/firmware-profiles"
if run "$tmp/moved/bin/cncstream" tiny.nc sim --yes --no-journal >"$tmp/missing.log" 2>&1; then
  cat "$tmp/missing.log"; fail "ran without any profile folder: it found profiles somewhere else"
fi
grep -qF "no firmware profile folder found" "$tmp/missing.log" || { cat "$tmp/missing.log"; fail "unclear error"; }
grep -qF "$tmp/moved/share/cncstream/firmware-profiles" "$tmp/missing.log" ||
  { cat "$tmp/missing.log"; fail "the error does not name the installed folder"; }
if grep -qF "$source_dir" "$tmp/missing.log"; then cat "$tmp/missing.log"; fail "looked in the source tree"; fi

# CNCSTREAM_PROFILES overrides.
cp -r "$source_dir/firmware-profiles" "$tmp/profiles"
CNCSTREAM_PROFILES="$tmp/profiles" XDG_STATE_HOME="$tmp/state" HOME="$tmp/home" \
  "$tmp/moved/bin/cncstream" tiny.nc sim --yes --no-journal </dev/null >"$tmp/env.log" 2>&1 ||
  { cat "$tmp/env.log"; fail "CNCSTREAM_PROFILES was not used"; }

echo "installed cncstream ran from $tmp/moved without the source tree"
