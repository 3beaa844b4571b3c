#!/usr/bin/env bash
# Every ```sh block of README.md runs as written: the blocks are extracted in
# order and each is run with bash -e in one scratch folder that holds the
# repository's data/, bench/ and docs/ and the build as build/ (the layout of
# a fresh clone after `make build`), so a block may use what an earlier one
# wrote (`view --load abrasion-out`, `wound --heal keloid-run`). Each must exit 0.
# Blocks that need what a test cannot have here are left to the test that
# covers them, and said so: `make ...` and the install/`cc` block
# (e2e_install), Python (e2e_python), Blender (e2e_blender), the viewer's
# window (e2e_view); `mpirun` blocks run when the build has MPI.
# SKINSIM_TEST_QUICK (the sanitizer build) runs the cheap blocks only.
# usage: e2e_readme.sh <skinsim> <source dir>
. "$(dirname "${BASH_SOURCE[0]}")/common.sh"
e2e_begin "$1"
SRC=$2
fail=0
W="$T/clone"
mkdir -p "$W"
for d in data bench docs examples integrations; do ln -s "$SRC/$d" "$W/$d"; done
ln -s "$(cd "$(dirname "$CLI")" && pwd)" "$W/build"
python3 - "$SRC/README.md" "$T" <<'EOF' || { echo "FAIL: cannot extract README blocks"; exit 1; }
import sys, re
text = open(sys.argv[1], encoding='utf-8').read()
blocks = re.findall(r'^```sh\n(.*?)^```', text, flags=re.S | re.M)
for i, b in enumerate(blocks):
    open(f'{sys.argv[2]}/block_{i:02d}.sh', 'w').write(b)
print(len(blocks), 'blocks')
EOF
has_mpi=0
command -v mpirun >/dev/null && "$CLI" --version 2>/dev/null | grep -qi 'mpi' && has_mpi=1
ran=0
for b in "$T"/block_*.sh; do
    name=$(basename "$b" .sh)
    first=$(grep -m1 -v '^#' "$b")
    why=""
    if grep -q '^make \|^cc \|pkg-config' "$b"; then why="make/install: e2e_install and make test"
    elif grep -q 'python3\|PYTHONPATH' "$b"; then why="Python: e2e_python"
    elif grep -q 'blender\|zip -r' "$b"; then why="Blender: e2e_blender"
    elif grep -q 'skinsim view' "$b"; then why="the viewer's window: e2e_view"
    elif grep -q 'mpirun' "$b" && [ $has_mpi = 0 ]; then why="this build has no MPI"
    elif [ -n "${SKINSIM_TEST_QUICK:-}" ] && grep -q 'heal\|wound\|optics table\|mpirun' "$b"; then
        why="SKINSIM_TEST_QUICK: long simulation"
    fi
    if [ -n "$why" ]; then
        echo "skip $name ($first ...): $why"
        continue
    fi
    start=$(date +%s)
    if (cd "$W" && bash -e "$b" >"$T/$name.out" 2>&1); then
        echo "ok   $name ($first ...) $(($(date +%s) - start)) s"
        ran=$((ran + 1))
    else
        echo "FAIL $name: README block exits non-zero:"; cat "$b"; tail -20 "$T/$name.out"
        fail=$((fail + 1))
    fi
done
[ $ran -gt 0 ] || { echo "FAIL: no README block ran"; exit 1; }
[ $fail -eq 0 ] || exit 1
echo "e2e_readme: $ran blocks ran as written"
