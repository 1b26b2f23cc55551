# Sourced by scripts/sanitize.sh and scripts/fuzz.sh: how the sanitizers report.
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1}
# file:line in stack traces; ASan refuses a symlink (Debian's llvm-symbolizer is one).
if symbolizer=$(command -v llvm-symbolizer); then
  export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-$(readlink -f "$symbolizer")}
fi
