# What the shell tests share (sourced by test_faults.sh and test_resume.sh):
# a tally of checks and the test of a metrics.csv of whole rows.
fails=0; passes=0
ok()  { passes=$((passes+1)); echo "ok: $1"; }
bad() { fails=$((fails+1)); echo "FAIL: $1"; }

# metrics.csv whole: a header, every row with the header's number of fields,
# and a last line ended. Prints why not.
rows_whole() {
  local f="$1"
  [ -f "$f" ] || { echo "no $f"; return 1; }
  [ -z "$(tail -c 1 "$f")" ] || { echo "$f: last line not ended"; return 1; }
  awk -F, 'NR == 1 { n = NF; if ($1 != "time_s") { print "no header"; exit 1 } next }
           NF != n { print "row " NR " has " NF " fields, not " n; exit 1 }' "$f"
}
