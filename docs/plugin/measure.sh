#!/usr/bin/env bash
# Reproduces the plugin measurements docs/plugin.md quotes: every run's printed summary goes to
# docs/plugin/runs/summary.txt and its JSON to docs/plugin/runs/<name>.json.
# Usage: docs/plugin/measure.sh [path to a profile binary of another commit, run alongside it
# as "<name>-before"; the stored runs have none].
set -euo pipefail
cd "$(dirname "$0")/../.."
cargo build --release --example profile
new=target/release/examples/profile
old=${1:-}
out=docs/plugin/runs
mkdir -p "$out"
: > "$out/summary.txt"
run() { # name binary args...
  local name=$1 bin=$2
  shift 2
  echo "== $name: profile $*" | tee -a "$out/summary.txt"
  "$bin" "$@" --json "$out/$name.json" | tee -a "$out/summary.txt"
}
for seed in 2 3; do
  for n in 1000 10000; do
    frames=600
    [ "$n" = 10000 ] && frames=300
    run "pile-$n-seed$seed" "$new" --scene pile --entities "$n" --threads 2 --budget-us 2000 --frames "$frames" --seed "$seed"
    if [ -n "$old" ]; then
      run "pile-$n-seed$seed-before" "$old" --scene pile --entities "$n" --threads 2 --budget-us 2000 --frames "$frames" --seed "$seed"
    fi
  done
done
run pile-1000-1thread "$new" --scene pile --entities 1000 --threads 1 --budget-us 2000 --frames 600 --seed 2
run pile-1000-unbudgeted "$new" --scene pile --entities 1000 --threads 2 --budget-us 0 --frames 600 --seed 2
run pile-1000-10000frames "$new" --scene pile --entities 1000 --threads 2 --budget-us 2000 --frames 10000 --seed 2
for t in 1 2; do
  run "pile-work-$t-threads" "$new" --scene pile --entities 1000 --threads "$t" --node-budget 200000 --frames 300 --seed 2
done
# The same pair again: thread scaling on this VM varies from run to run.
for t in 1 2; do
  run "pile-work-$t-threads-again" "$new" --scene pile --entities 1000 --threads "$t" --node-budget 200000 --frames 300 --seed 2
done
# 10 000 bodies: where the time goes frame by frame, and a run twice as long (the pile lands).
"$new" --scene pile --entities 10000 --threads 2 --budget-us 2000 --frames 300 --seed 2 \
  --frames-csv "$out/pile-10000-seed2-frames.csv" > "$out/pile-10000-seed2-frames.txt"
run pile-10000-seed2-600frames "$new" --scene pile --entities 10000 --threads 2 --budget-us 2000 --frames 600 --seed 2
for scene in cannonball cloth intestine; do
  run "$scene" "$new" --scene "$scene" --threads 2
done
for k in 2 3; do
  run "cannonball-run$k" "$new" --scene cannonball --threads 2
done
if [ -n "$old" ]; then
  for k in 1 2 3; do
    run "cannonball-before-run$k" "$old" --scene cannonball --threads 2
  done
fi
# The cannonball example under its work budget, three alternating runs of each build (the old
# one: the cannonball example built from the same commit as the old profile, beside it).
{
  for k in 1 2 3; do
    echo "== this commit: cargo run --release --example cannonball (run $k)"
    cargo run --release --quiet --example cannonball
    if [ -n "$old" ]; then
      echo "== before: cannonball (run $k)"
      "$(dirname "$old")/cannonball"
    fi
  done
} > "$out/cannonball-example.txt" 2>&1
"$new" --scene pile --entities 1000 --threads 2 --budget-us 2000 --frames 600 --seed 1 \
  --json docs/plugin/pile.json --svg docs/plugin/pile_timeline.svg | tee -a "$out/summary.txt"
