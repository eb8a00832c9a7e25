#!/usr/bin/env bash
# The nightly robustness sweep (docs/nightly.md): runs STUDY into OUT_ROOT/<UTC time>, which records
# itself in the run history and compares itself with the study's previous run there (diff.md and
# report.html in the run's directory), points OUT_ROOT/latest at it, and exits as `flexfarm diff`:
#   0  nothing got worse than the previous night (or this is the first night)
#   1  a regression: a metric worse than its tolerance beyond noise, more failed variants, a worse verdict
#   2  bad input, or the run could not finish (its log: OUT_ROOT/<time>.log)
# Usage: nightly.sh [STUDY] [OUT_ROOT]; environment: FLEXFARM (the binary, default `flexfarm` on the
# PATH), FLEXFARM_HISTORY (the run history; default ~/.local/share/flexfarm), FLEXFARM_NIGHT (the run's
# name instead of the time).
set -uo pipefail
flexfarm=${FLEXFARM:-flexfarm}
study=${1:-configs/studies/fbtb_robustness.yaml}
root=${2:-out/nightly}
night=${FLEXFARM_NIGHT:-$(date -u +%Y-%m-%dT%H%M%SZ)}
out=$root/$night
mkdir -p "$root" || exit 2

# The sweep. Exit 3 (some variants failed numerically) still has results, and the diff counts them.
"$flexfarm" run "$study" --out "$out" >"$out.log" 2>&1
status=$?
if [[ $status -ne 0 && $status -ne 3 ]]; then
  echo "nightly: flexfarm run $study failed (exit $status); see $out.log" >&2
  tail -n 5 "$out.log" >&2
  exit 2
fi
ln -sfn "$night" "$root/latest"

# What changed since the previous night: the run wrote diff.md when there was one to compare with.
if [[ ! -f $out/diff.md ]]; then
  echo "nightly: $out: the first run of $study in the history; report: $out/report.html"
  exit 0
fi
"$flexfarm" diff "$out" >/dev/null
status=$?
case $status in
  0) echo "nightly: $out: nothing got worse; report: $out/report.html" ;;
  1) echo "nightly: $out: REGRESSION, see $out/diff.md; report: $out/report.html" >&2 ;;
  *) echo "nightly: $out: flexfarm diff failed (exit $status)" >&2 ;;
esac
exit $status
