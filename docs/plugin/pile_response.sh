#!/usr/bin/env bash
# The pile example with the built-in impulse response, with and without a budget: how many
# bodies stay in the box and fall asleep. Output: docs/plugin/runs/pile_response.txt.
# Usage: docs/plugin/pile_response.sh [path to a pile binary of another commit, run after each
# run of this one as "before"].
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --example pile
new=target/release/examples/pile
old=${1:-}
out=docs/plugin/runs/pile_response.txt
mkdir -p "$(dirname "$out")"
: > "$out"
for args in "500 240 2000" "1000 600 2000" "1000 600 0" "4000 600 2000" "4000 600 0"; do
  # shellcheck disable=SC2086
  { echo "== pile $args"; "$new" $args --svg target/pile_response.svg; } | tee -a "$out"
  if [ -n "$old" ]; then
    # shellcheck disable=SC2086
    { echo "== before: pile $args"; "$old" $args --svg target/pile_response_before.svg; } | tee -a "$out"
  fi
done
