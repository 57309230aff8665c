# What the shell tests share (sourced by test_faults.sh and test_resume.sh):
# a tally of checks, the test of a metrics.csv of whole rows, and a wait for a
# run's first output.
fails=0; passes=0
ok()  { passes=$((passes+1)); echo "ok: $1"; }
bad() { fails=$((fails+1)); echo "FAIL: $1"; }

# metrics.csv whole: a header, every row with the header's number of fields,
# and a last line ended. Prints why not. `rows_whole FILE killed`: the file of
# a run killed by SIGKILL, which may also end with a row cut short at a page
# boundary: Linux ends a buffered write() part way when SIGKILL comes between
# two of its pages (mm/filemap.c generic_perform_write checks for a fatal
# signal before each), and no program can catch SIGKILL to finish it; that row
# is past the checkpoint's metrics.csv bytes, and --resume cuts it back.
PAGE=$(getconf PAGESIZE)
rows_whole() {
  local f="$1" killed="${2:-}" cut=0
  [ -f "$f" ] || { echo "no $f"; return 1; }
  if [ -n "$(tail -c 1 "$f")" ]; then
    local size; size=$(stat -c %s "$f")
    [ -n "$killed" ] && [ $((size % PAGE)) -eq 0 ] ||
      { echo "$f: last line not ended ($size bytes, a page is $PAGE)"; return 1; }
    cut=1
  fi
  awk -F, -v cut=$cut 'NR == 1 { n = NF; if ($1 != "time_s") { print "no header"; exit 1 } next }
           after { print after; exit 1 }
           NF != n { why = "row " NR " has " NF " fields, not " n; if (cut && NF < n) after = why; else { print why; exit 1 } }
           END { if (NR == 0) { print "empty"; exit 1 } }' "$f"
}
# Waits until FILE is not empty or the run PID has ended: at most a minute (a
# loaded machine can take seconds to start a run).
wait_for() {
  local i
  for i in $(seq 6000); do
    [ -s "$1" ] && return 0
    kill -0 "$2" 2>/dev/null || return 1
    sleep 0.01
  done
  return 1
}
