# The harness of the command-line tests (sourced): a fresh working folder removed at exit,
# check NAME CONDITION… counting passes and failures, refused EXPECTED ARGS… (non-zero exit,
# the message on stderr, nothing written to ./out), and finish (the count, the exit status).
# Needs $LMCAL, the binary.
: "${LMCAL:?set LMCAL to the lmcal binary}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
failures=0
pass=0

check() {  # check NAME CONDITION...
  local name=$1; shift
  if "$@"; then pass=$((pass + 1)); else echo "FAILED: $name"; failures=$((failures + 1)); fi
}

# Refused: a non-zero exit, the message, and nothing written in ./out (give -o out).
refused() {  # refused EXPECTED_TEXT ARGS...
  local expected=$1; shift
  rm -rf out; mkdir out
  "$LMCAL" "$@" >stdout.txt 2>stderr.txt
  local rc=$?
  if [[ $rc -eq 0 ]]; then echo "  accepted: $*"; return 1; fi
  if ! grep -qF -- "$expected" stderr.txt; then echo "  message lacks '$expected': $(cat stderr.txt)"; return 1; fi
  if [[ -n "$(ls -A out)" ]]; then echo "  wrote output despite the error: $(ls out)"; return 1; fi
  return 0
}

finish() {  # finish NAME
  echo "$1: $pass passed, $failures failed"
  exit $((failures > 0))
}
