#!/usr/bin/env bash
# tools/tidy.sh BUILD_DIR [FILE...]
#
# Runs clang-tidy 14 with the repository's .clang-tidy over every translation
# unit of src/ and sim/ in BUILD_DIR/compile_commands.json (a configured build
# folder is enough: the one generated source, openapi_json.cpp, is not ours to
# check and no header is generated). The project's headers are checked through
# the files that include them (HeaderFilterRegex). Prints only the findings;
# exits 1 when there is any, 2 when it cannot run. FILEs (of src/ or sim/)
# check only those.
#
# Works from a GCC build's and from a clang build's compilation database.
# Environment: CLANG_TIDY (default clang-tidy-14), TIDY_JOBS (default nproc),
# TIDY_TIMES=FILE writes each file's wall, user and system seconds to FILE.
set -euo pipefail

die() { echo "tidy.sh: $*" >&2; exit 2; }
[[ $# -ge 1 ]] || die "usage: tools/tidy.sh BUILD_DIR [FILE...]"
[[ -d $1 ]] || die "no such build folder: $1"
build_dir=$(cd "$1" && pwd)
shift
only=()
for f in "$@"; do
  [[ -f $f ]] || die "no such file: $f"
  only+=("$(realpath "$f")")
done
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tidy=${CLANG_TIDY:-clang-tidy-14}
jobs=${TIDY_JOBS:-$(nproc)}
[[ -f $build_dir/compile_commands.json ]] ||
  die "$build_dir/compile_commands.json is missing: configure first (cmake -S . -B $1)"
command -v "$tidy" >/dev/null || die "$tidy not found (Debian: apt-get install clang-tidy-14)"
[[ -f $root/.clang-tidy ]] || die "$root/.clang-tidy is missing"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# A compilation database of src/ and sim/ only. The app's files that CMake
# compiles in unity batches (UNITY_BUILD: each includes CLI11, a heavy
# header-only library) are checked in the same batches, which costs a third of
# checking them one by one; findings still name the real file. Each batch is
# a file of our own that includes the batch's sources, with the batch's
# command.
python3 - "$root" "$build_dir/compile_commands.json" "$work" "${only[@]}" <<'PY'
import json, os, re, sys
root, db_path, work = sys.argv[1:4]
only = set(sys.argv[4:])
ours = (os.path.join(root, 'src') + os.sep, os.path.join(root, 'sim') + os.sep)
entries, batches = [], {}
for e in json.load(open(db_path)):
    path = os.path.normpath(os.path.join(e['directory'], e['file']))
    if re.search(r'/unity_[0-9]+_cxx\.cxx$', path):
        members = [inc for inc in re.findall(r'^#include "([^"]+)"', open(path).read(), re.M)
                   if inc.startswith(ours)]
        if members:
            batch = os.path.join(work, 'batch%d.cpp' % len(batches))
            open(batch, 'w').write(''.join(
                '#include "%s"  // NOLINT(bugprone-suspicious-include): a unity batch\n' % m for m in members))
            command = e['command'].replace(e['file'], batch) if 'command' in e else None
            arguments = [batch if a == e['file'] else a for a in e.get('arguments', [])]
            batch_entry = dict(e, file=batch, output=batch + '.o')
            if command is not None:
                batch_entry['command'] = command
            else:
                batch_entry['arguments'] = arguments
            batches[batch] = (batch_entry, members)
    elif path.startswith(ours):
        entries.append(dict(e, file=path))
# A source of a batch that a test program also compiles on its own is
# checked once, with its batch.
in_batches = {m for _, members in batches.values() for m in members}
seen, db = set(), []
for e in entries:
    if e['file'] not in seen and e['file'] not in in_batches:
        seen.add(e['file'])
        db.append(e)
members_of = {}
for batch, (entry, members) in batches.items():
    seen.add(batch)
    db.append(entry)
    members_of[batch] = members
if not db:
    print('tidy.sh: no file of src/ or sim/ in ' + db_path, file=sys.stderr)
    sys.exit(2)
if only:
    # A file of a batch is checked with its batch.
    wanted = {b for b, m in members_of.items() if only & set(m)} | (only & seen)
    missing = only - seen - {m for ms in members_of.values() for m in ms}
    if missing:
        print('tidy.sh: not a file of src/ or sim/ in the build: ' + ' '.join(sorted(missing)), file=sys.stderr)
        sys.exit(2)
    seen, db = wanted, [e for e in db if e['file'] in wanted]
json.dump(db, open(os.path.join(work, 'compile_commands.json'), 'w'), indent=1)
# Slowest first, so that the last to finish is a short one: the files that
# include Boost.Beast or Boost.Asio take several times as long as the others.
def weight(path):
    text = ''.join(open(p, errors='replace').read() for p in members_of.get(path, [path]))
    return 3 if path in members_of else 2 if 'boost/beast' in text else 1 if 'boost/asio' in text else 0
files = sorted(seen, key=lambda p: (-weight(p), p))
open(os.path.join(work, 'files'), 'w').write('\n'.join(files) + '\n')
PY

mkdir "$work/out"
export tidy work root
# -Wno-unknown-warning-option: a GCC build's command may name warnings clang
# does not know (-Wno-maybe-uninitialized). The command's own warnings
# (-Wall -Wextra) are findings too, as clang sees them (clang-diagnostic-*).
# --config-file: the batches lie outside the repository, where clang-tidy
# would not find .clang-tidy.
check_one() {
  local file=$1 out rc=0 TIMEFORMAT="%R %U %S"
  out=$work/out/$(printf '%s' "$file" | tr '/' '_')
  { time "$tidy" -p "$work" --config-file="$root/.clang-tidy" --quiet \
    --extra-arg=-Wno-unknown-warning-option "$file" >"$out" 2>&1 || rc=$?; } 2>"$out.time"
  echo "$rc" >"$out.rc"
  echo "${file#"$root"/}" >>"$out.time"
}
export -f check_one
xargs -a "$work/files" -d '\n' -P "$jobs" -I{} bash -c 'check_one "$1"' _ {}

# The findings, each once (a header's is reported by every file that includes
# it), without clang's "N warnings generated." lines; a count by check after.
python3 - "$work" "${TIDY_TIMES:-}" <<'PY'
import collections, glob, os, re, sys
work, times = sys.argv[1:3]
head = re.compile(r'^\S.*:\d+:\d+: (warning|error): .*\[([^,\]]+)')
blocks, seen, failed = [], set(), []
for rc_path in sorted(glob.glob(os.path.join(work, 'out', '*.rc'))):
    log = rc_path[:-3]
    rc = open(rc_path).read().strip()
    block = []
    for line in open(log, errors='replace').read().splitlines() + [None]:
        if line is None or head.match(line) or re.match(r'^(Error while processing|error: )', line):
            if block and tuple(block) not in seen:
                seen.add(tuple(block))
                blocks.append(block)
            block = [line] if line is not None else []
        elif not re.match(r'^[0-9]+ (warnings?|errors?)( and [0-9]+ errors?)? generated\.$', line):
            block.append(line)
    if rc != '0':
        failed.append(open(log + '.time').read().split()[-1])
by_check = collections.Counter()
for block in blocks:
    print('\n'.join(block))
    m = head.match(block[0])
    by_check[m.group(2) if m else 'clang-tidy'] += 1
if times:
    rows = [open(t).read().split() for t in glob.glob(os.path.join(work, 'out', '*.time'))]
    rows.sort(key=lambda r: -float(r[0]))
    with open(times, 'w') as f:
        f.write('# wall user system (seconds) file, slowest first\n')
        for r in rows:
            f.write(' '.join(r) + '\n')
        f.write('# total user+system: %.1f s\n' % sum(float(r[1]) + float(r[2]) for r in rows))
files = open(os.path.join(work, 'files')).read().split()
if blocks or failed:
    print('tidy.sh: %d finding(s) in the %d files of src/ and sim/: %s' % (
        len(blocks), len(files), ', '.join('%s %d' % kv for kv in by_check.most_common())), file=sys.stderr)
    if failed and not blocks:
        print('tidy.sh: clang-tidy failed on ' + ' '.join(failed), file=sys.stderr)
    sys.exit(1)
PY
