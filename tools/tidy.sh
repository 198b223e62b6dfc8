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

# A compilation database of src/ and sim/ only, in batches. clang-tidy 14's
# matchers walk the whole AST, system and library headers included, so a
# file's cost is mostly what it includes: a batch (a file of the script's own
# that includes several sources of one folder compiled with the same command)
# pays for those headers once. Findings still name the real file. The app's
# files, which CMake already compiles in unity batches (CLI11), are checked in
# those batches. A batch whose sources do not compile together (two files
# with the same name in an anonymous namespace) is checked again file by file
# (see below), so batching never hides or invents a finding.
python3 - "$root" "$build_dir/compile_commands.json" "$work" "${only[@]}" <<'PY'
import json, os, re, sys
root, db_path, work = sys.argv[1:4]
only = set(sys.argv[4:])
ours = (os.path.join(root, 'src') + os.sep, os.path.join(root, 'sim') + os.sep)
BATCH_SIZE = 8
batches = {}  # batch file -> (entry, members)
def new_batch(entry, members, source_file):
    batch = os.path.join(work, 'batch%d.cpp' % len(batches))
    open(batch, 'w').write(''.join(
        '#include "%s"  // NOLINT(bugprone-suspicious-include): a batch\n' % m for m in members))
    b = dict(entry, file=batch, output=batch + '.o')
    if 'command' in entry:
        b['command'] = entry['command'].replace(source_file, batch)
    else:
        b['arguments'] = [batch if a == source_file else a for a in entry['arguments']]
    batches[batch] = (b, members)
entries = []
for e in json.load(open(db_path)):
    path = os.path.normpath(os.path.join(e['directory'], e['file']))
    if re.search(r'/unity_[0-9]+_cxx\.cxx$', path):
        members = [inc for inc in re.findall(r'^#include "([^"]+)"', open(path).read(), re.M)
                   if inc.startswith(ours)]
        if members:
            new_batch(e, members, e['file'])
    elif path.startswith(ours):
        entries.append(dict(e, file=path))
# A source of a unity batch that a test program also compiles on its own is
# checked once, with its batch; any other source once, with the first command
# the database gives it.
in_unity = {m for _, members in batches.values() for m in members}
singles, seen = {}, set()
for e in entries:
    if e['file'] not in seen and e['file'] not in in_unity:
        seen.add(e['file'])
        singles[e['file']] = e
if only:
    # A file of a unity batch is checked with its batch; the others alone.
    known = set(singles) | in_unity
    missing = only - known
    if missing:
        print('tidy.sh: not a file of src/ or sim/ in the build: ' + ' '.join(sorted(missing)), file=sys.stderr)
        sys.exit(2)
    batches = {b: v for b, v in batches.items() if only & set(v[1])}
    singles = {f: e for f, e in singles.items() if f in only}
if not batches and not singles:
    print('tidy.sh: no file of src/ or sim/ in ' + db_path, file=sys.stderr)
    sys.exit(2)
unity_batches = set(batches)
# The rest in batches of up to BATCH_SIZE files of one folder and one command.
def command_key(e):
    words = e['command'].split() if 'command' in e else list(e['arguments'])
    out, skip = [], False
    for w in words:
        if skip:
            skip = False
        elif w == '-o':
            skip = True
        elif w != e['file'] and not w.endswith(os.path.basename(e['file'])):
            out.append(w)
    return (os.path.dirname(e['file']), e['directory'], tuple(out))
groups = {}
for f in sorted(singles):
    groups.setdefault(command_key(singles[f]), []).append(f)
for files in groups.values():
    if len(files) == 1 or only:
        continue
    for i in range(0, len(files), BATCH_SIZE):
        part = files[i:i + BATCH_SIZE]
        if len(part) > 1:
            e = singles[part[0]]
            new_batch(e, part, e['file'])
            for f in part:
                del singles[f]
db = list(singles.values()) + [b for b, _ in batches.values()]
json.dump(db, open(os.path.join(work, 'compile_commands.json'), 'w'), indent=1)
# The members of the script's own batches, for the file-by-file check of a
# batch that does not compile.
os.mkdir(os.path.join(work, 'alone'))
first_entry = {}
for e in entries:
    first_entry.setdefault(e['file'], e)
alone = [first_entry[m] for b, (_, members) in batches.items() if b not in unity_batches for m in members]
json.dump(alone, open(os.path.join(work, 'alone', 'compile_commands.json'), 'w'), indent=1)
json.dump({b: members for b, (_, members) in batches.items() if b not in unity_batches},
          open(os.path.join(work, 'own_batches.json'), 'w'))
# Slowest first, so that the last to finish is a short one: the files that
# include Boost.Beast or Boost.Asio take several times as long as the others.
def weight(path):
    members = batches[path][1] if path in batches else [path]
    text = ''.join(open(p, errors='replace').read() for p in members)
    return (3 if path in unity_batches else 2 if 'boost/beast' in text else 1 if 'boost/asio' in text else 0,
            len(members))
files = sorted([e['file'] for e in db], key=lambda p: (weight(p), p), reverse=True)
open(os.path.join(work, 'files'), 'w').write('\n'.join(files) + '\n')
open(os.path.join(work, 'sources'), 'w').write('%d\n' % (len(singles) + sum(len(m) for _, m in batches.values())))
PY

mkdir "$work/out"
export tidy work root
# -Wno-unknown-warning-option: a GCC build's command may name warnings clang
# does not know (-Wno-maybe-uninitialized). The command's own warnings
# (-Wall -Wextra) are findings too, as clang sees them (clang-diagnostic-*).
# --config-file: the batches lie outside the repository, where clang-tidy
# would not find .clang-tidy.
check_one() {  # check_one FILE [DATABASE_DIR]
  local file=$1 db=${2:-$work} out rc=0 TIMEFORMAT="%R %U %S"
  out=$work/out/$(printf '%s' "$file" | tr '/' '_')
  { time "$tidy" -p "$db" --config-file="$root/.clang-tidy" --quiet \
    --extra-arg=-Wno-unknown-warning-option "$file" >"$out" 2>&1 || rc=$?; } 2>"$out.time"
  echo "$rc" >"$out.rc"
  echo "${file#"$root"/}" >>"$out.time"
}
export -f check_one
xargs -a "$work/files" -d '\n' -P "$jobs" -I{} bash -c 'check_one "$1"' _ {}

# A batch whose files do not compile together (a clang error, such as two
# helpers of one name in anonymous namespaces) says nothing about them: its
# output is set aside (its time still counts) and its files are checked one by
# one.
python3 - "$work" "$root" >"$work/again" <<'PY'
import json, os, sys
work, root = sys.argv[1:3]
for batch, members in json.load(open(os.path.join(work, 'own_batches.json'))).items():
    out = os.path.join(work, 'out', batch.replace('/', '_'))
    text = open(out, errors='replace').read()
    if '[clang-diagnostic-error]' in text or 'Error while processing' in text:
        os.rename(out, out + '.set-aside')
        os.remove(out + '.rc')
        print('tidy.sh: %s did not compile as one batch; checked file by file' %
              ', '.join(os.path.relpath(m, root) for m in members), file=sys.stderr)
        print('\n'.join(members))
PY
if [[ -s $work/again ]]; then
  xargs -a "$work/again" -d '\n' -P "$jobs" -I{} bash -c 'check_one "$1" "$work/alone"' _ {}
fi

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
units = len(open(os.path.join(work, 'files')).read().split())
where = 'the %s files of src/ and sim/ (%d translation units)' % (open(os.path.join(work, 'sources')).read().strip(), units)
if not blocks and not failed:
    print('tidy.sh: no finding in ' + where, file=sys.stderr)
if blocks or failed:
    print('tidy.sh: %d finding(s) in %s: %s' % (
        len(blocks), where, ', '.join('%s %d' % kv for kv in by_check.most_common())), file=sys.stderr)
    if failed and not blocks:
        print('tidy.sh: clang-tidy failed on ' + ' '.join(failed), file=sys.stderr)
    sys.exit(1)
PY
