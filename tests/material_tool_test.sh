#!/usr/bin/env bash
# sinew-material along the uniaxial path to stretch 3.4 at nu = 0.49 (Sec. 5.2, Fig. 6): Stable
# Neo-Hookean keeps J within 3% of 1, corotational collapses (J < 0.01). Checks the exit codes and
# the CSV's numbers, not only its header. Usage: material_tool_test.sh SINEW_MATERIAL WORKDIR
set -euo pipefail
tool=$1 work=$2
mkdir -p "$work"
"$tool" --model stable-neohookean --nu 0.49 --path uniaxial --max 3.4 --steps 24 --output "$work/snh.csv"
"$tool" --model corotational --nu 0.49 --path uniaxial --max 3.4 --steps 24 --output "$work/cr.csv"
last() { tail -n 1 "$1"; }
col() { awk -F, -v c="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == c) k = i; next } { v = $k } END { print v }' "$1"; }
[ "$(head -n 1 "$work/snh.csv" | cut -d, -f1-3)" = "stretch,J,psi" ] || { echo "FAIL: bad CSV header"; exit 1; }
[ "$(wc -l < "$work/snh.csv")" -eq 26 ] || { echo "FAIL: expected 25 rows"; exit 1; }
s=$(col "$work/snh.csv" stretch) j_snh=$(col "$work/snh.csv" J) j_cr=$(col "$work/cr.csv" J)
echo "stretch $s: J = $j_snh (stable-neohookean), $j_cr (corotational)"
awk -v s="$s" -v a="$j_snh" -v b="$j_cr" 'BEGIN {
  if (s < 3.399 || s > 3.401) { print "FAIL: last stretch " s; exit 1 }
  if (a < 0.97 || a > 1.03) { print "FAIL: SNH J " a " not within 3% of 1"; exit 1 }
  if (!(b < 0.01)) { print "FAIL: corotational J " b " did not collapse"; exit 1 }
}'
echo "material tool ok"
