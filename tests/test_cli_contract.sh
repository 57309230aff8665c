#!/bin/bash
# The command line's contract: the --help of every command and the exit code
# of each case in tests/cli_contract/cases.txt, held against
# tests/cli_contract/expected.txt (captured before the run and sweep moved
# into the library, issue 40). A change to either is a change users see: make
# it on purpose, with `tests/test_cli_contract.sh build/wetcloth . --update`.
# Usage: test_cli_contract.sh WETCLOTH SOURCE_DIR [--update]
set -u
W=$(realpath "$1"); SRC=$(realpath "$2"); UPDATE=${3:-}
CASES="$SRC/tests/cli_contract/cases.txt"
EXPECTED="$SRC/tests/cli_contract/expected.txt"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
# argv[0] "wetcloth", as a user types it: CLI11's usage lines name it.
mkdir "$T/bin" && ln -s "$W" "$T/bin/wetcloth"
export PATH="$T/bin:$PATH"
cd "$T" || exit 1
mkdir run && cd run || exit 1  # cases write their outputs here
while IFS= read -r line; do
  [ -z "$line" ] || [ "${line:0:1}" = "#" ] && continue
  # A help case records its output; another case its exit code alone (its
  # message may name this run's temporary folder).
  # "sh: ..." is a line for the shell as it stands (a signal's case).
  cmd="wetcloth $line"; [ "${line:0:4}" = "sh: " ] && cmd=${line:4}
  out=$(eval "$cmd" 2>"$T/err" </dev/null); code=$?
  echo "\$ $cmd"
  echo "exit $code"
  case " $line " in
    *" --help "*|*" -h "*|*" --version "*) printf '%s\n' "$out"; cat "$T/err" ;;
  esac
done < "$CASES" > "$T/got.txt"
if [ "$UPDATE" = "--update" ]; then
  cp "$T/got.txt" "$EXPECTED" && echo "wrote $EXPECTED" && exit 0
fi
if diff -u "$EXPECTED" "$T/got.txt" > "$T/diff"; then
  echo "ok: $(grep -c '^\$ ' "$EXPECTED") cases: the help texts and exit codes as captured"
  exit 0
fi
echo "FAIL: the command line differs from tests/cli_contract/expected.txt:"
cat "$T/diff"
exit 1
