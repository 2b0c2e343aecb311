# Sourced by the tool tests: expect CODE PATTERN -- command... runs the command and checks its
# exit code and that its output (stdout and stderr) matches the grep pattern; sets fail=1 if not.
fail=0
expect() {
  local code=$1 pattern=$2; shift 3
  local out rc
  out=$("$@" 2>&1); rc=$?
  if [ "$rc" != "$code" ] || ! grep -q -- "$pattern" <<<"$out"; then
    echo "FAIL: '$*' exited $rc (want $code), output: $out (want /$pattern/)"; fail=1
  else
    echo "ok: $* -> $rc: $(head -1 <<<"$out")"
  fi
}
