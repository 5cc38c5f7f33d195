#!/usr/bin/env bash
# The outside users' files of session 10 through the CLI: one line per file.
# Usage (from the repository root): benchmarks/outside_users/check.sh [IWANFE]
set -u
IWANFE=${1:-.venv/bin/iwanfe}
HERE=$(cd "$(dirname "$0")" && pwd)
verdict='import json,sys; r=json.load(sys.stdin); print(r["cause"], "+".join(r["also"]), "ambiguous" if r["ambiguous"] else "")'
echo "# tables: diagnose verdict"
for f in "$HERE"/tables/*.csv; do
  printf '%-32s %s\n' "$(basename "$f")" "$("$IWANFE" diagnose "$f" --json 2>/dev/null | python3 -c "$verdict" 2>/dev/null || echo ERROR)"
done
echo "# malformed tables and case files: exit status, first line of stderr"
for f in "$HERE"/tables/bad/*.csv "$HERE"/case_files/bad/*.toml; do
  case "$f" in *.csv) cmd=(diagnose "$f");; *) cmd=(case check "$f");; esac
  err=$("$IWANFE" "${cmd[@]}" 2>&1 >/dev/null | head -1); rc=$?
  "$IWANFE" "${cmd[@]}" >/dev/null 2>&1; rc=$?
  printf '%-28s exit %s  %s\n' "$(basename "$f")" "$rc" "${err:0:110}"
done
echo "# case files: exit status of each FE command"
for f in "$HERE"/case_files/cantilever-steel-3bolt.toml "$HERE"/case_files/freefree-al-lap.toml; do
  for c in "case check" "modes --case" "backbone --mode 2 --case" "update --case" "diagnose --case"; do
    "$IWANFE" $c "$f" >/dev/null 2>&1
    printf '%-32s %-26s exit %s\n' "$(basename "$f")" "$c" "$?"
  done
done
