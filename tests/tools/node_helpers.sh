# Sourced by the jpcr_node script tests after setting $build and $src: the programs, a temporary
# folder, background processes ($pids) ended on exit, expect (expect.sh), the loopback Cyclone
# configuration and a domain of this process's own; bounded waits for background processes and
# the comparison of a received path with a trajectory file.
synth=$build/tools/jpcr_synth
run=$build/tools/jpcr_run
node=$build/tools/jpcr_node
play=$build/tools/jpcr_dds_play
echo_bin=$build/tools/jpcr_dds_echo
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  rm -rf "$tmp"
}
trap cleanup EXIT
# shellcheck source=expect.sh
source "$src/tests/tools/expect.sh"
export CYCLONEDDS_URI="file://$src/configs/cyclonedds_loopback.xml"
domain=$(( $$ % 200 + 11 ))

# The split deployment's parameters into $tmp/params.yaml: a keyframe every $1 m, deep input and
# result histories (no frame or path dropped while the nodes work), a back-end queue of one
# keyframe (the front end waits for the back end whenever it is ahead).
split_params() {
  printf 'frontend:\n  tracker:\n    keyframe_translation: %s\n' "$1" > "$tmp/params.yaml"
  printf 'dds:\n  history_depth: 64\n  image_history_depth: 16\n  keyframe_queue: 1\n' \
    >> "$tmp/params.yaml"
}

# Waits up to $2 s for pid $1 and returns its exit code (124 after killing it on timeout).
wait_bounded() {
  local pid=$1 limit=$2 i
  for ((i = 0; i < limit * 10; ++i)); do
    kill -0 "$pid" 2>/dev/null || { wait "$pid"; return $?; }
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null; wait "$pid" 2>/dev/null; return 124
}

# Waits up to $2 s for the node, pid $1, and checks that it exited 0 with a line of its output
# file $3 matching $4; $5 names the case in the message.
expect_node() {
  local pid=$1 limit=$2 file=$3 pattern=$4 label=$5 rc
  wait_bounded "$pid" "$limit"; rc=$?
  if [ $rc != 0 ] || ! grep -q "$pattern" "$file"; then
    echo "FAIL: $label: exit $rc"; cat "$file"; fail=1
  else
    echo "ok: $label: $(grep -m1 "$pattern" "$file")"
  fi
}

# The final TUM block a `jpcr_dds_echo --tum` of a path printed == a trajectory file, to 1e-9;
# with a third argument `union`, the last pose of each stamp over every block printed (the paths
# of keep_history: false, each holding the frames made final since the one before).
same_path() {
  /usr/bin/python3 - "$1" "$2" "${3:-}" <<'PY'
import sys
def poses(lines):
    return [[float(x) for x in l.split()] for l in lines if l.strip() and not l.startswith(("#", "path "))]
echo = open(sys.argv[1]).read().splitlines()
starts = [i for i, l in enumerate(echo) if l.startswith("path ")]
if not starts:
    sys.exit("no path received")
want = poses(open(sys.argv[2]).read().splitlines())
if sys.argv[3] == "union":  # every path's poses, the last one of each stamp
    bounds = starts + [len(echo)]
    for a, b in zip(bounds, bounds[1:]):
        stamps = [round(p[0], 6) for p in poses(echo[a + 1:b])]
        if len(set(stamps)) != len(stamps):
            sys.exit("a path holds a frame twice: %s" % stamps)
    last = {round(p[0], 6): p for p in poses(echo)}
    missing = [w[0] for w in want if round(w[0], 6) not in last]
    if missing:
        sys.exit("no path held the frames stamped %s" % missing)
    got = [last[round(w[0], 6)] for w in want]
else:
    got = poses(echo[starts[-1] + 1:])
if len(got) != len(want):
    sys.exit("final path has %d poses, the file %d" % (len(got), len(want)))
worst = 0.0
for g, w in zip(got, want):
    if abs(g[0] - w[0]) > 1e-6:
        sys.exit("stamp %r != %r" % (g[0], w[0]))
    s = 1.0 if sum(a * b for a, b in zip(g[4:], w[4:])) >= 0 else -1.0
    worst = max([worst] + [abs(a - b) for a, b in zip(g[1:4], w[1:4])] +
                [abs(s * a - b) for a, b in zip(g[4:], w[4:])])
if worst > 1e-9:
    sys.exit("poses differ by %g" % worst)
print("ok: %d poses equal to %g" % (len(got), worst))
PY
}