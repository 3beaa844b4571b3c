# Shared preamble of the end-to-end scripts (tests/e2e_*.sh), sourced:
#
#   . "$(dirname "${BASH_SOURCE[0]}")/common.sh"
#   e2e_begin "$1"          # $CLI: the command, absolute; $T: a scratch folder
#
# Two styles of check live side by side: `fail MSG` stops the script at the
# first failure; `check 'TEST' MSG` / `ok` / `bad MSG` count, and the script
# ends with `[ $fail -eq 0 ]`. This file is not a test itself (ctest runs
# only tests/e2e_*.sh).
set -u

fail=0
pass=0

# The command's absolute path (the scripts cd into scratch folders) and a
# scratch folder named after the script, removed however the script ends.
e2e_begin() {
  CLI="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
  T=$(mktemp -d "/tmp/skinsim-$(basename "$0" .sh)-XXXXXX")
  trap 'rm -rf "$T"' EXIT
}

fail() { echo "FAIL: $*" >&2; exit 1; }
ok() { pass=$((pass + 1)); }
bad() { echo "FAIL: $*"; fail=$((fail + 1)); }
check() { if eval "$1"; then ok; else bad "$2"; fi; }

# The command (all the arguments) exits 2 with an error message; else stop.
exits2() {
  "$@" >"$T/o.txt" 2>"$T/e.txt"
  local rc=$?
  [ $rc -eq 2 ] || fail "expected exit 2, got $rc: $*"
  grep -q "error" "$T/e.txt" || fail "no error message: $*"
}
# The file starts with the PNG signature.
png_ok() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "$1 is not a PNG"; }
# One top-level key of a JSON file.
jget() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))[sys.argv[2]])" "$1" "$2"; }
# md5 of every file under a folder, by relative path (to compare two trees).
sums() { (cd "$1" && find . -type f | LC_ALL=C sort | xargs md5sum) 2>/dev/null; }
