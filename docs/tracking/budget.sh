#!/usr/bin/env bash
# The tracker under a time budget per step (TrackerConfig::time_budget, tracking_quality
# --budget-us) on held-out shared meshes and seeds (not the ones its constants were chosen on),
# a budget of about 0.2x the exact self pass's time per frame on each mesh (self_contacts_excluding,
# as docs/tracking/held_out measured it). Output:
# docs/tracking/budget/output.txt and one JSON per run.
set -euo pipefail
cd "$(dirname "$0")/../.."
meshes=${STOCHASTIC_COLLISION_MESHES:-../shared/assets/meshes}
cargo build --release --example tracking_quality
q=target/release/examples/tracking_quality
out=docs/tracking/budget
: > "$out/output.txt"
for run in "bunny 800" "teapot 1600" "large_intestine_20k 3500"; do
  set -- $run
  mesh=$1 budget=$2
  for seed in 3 4 5; do
    echo "== $mesh seed $seed, --budget-us $budget" | tee -a "$out/output.txt"
    "$q" --mesh "$meshes/$mesh.obj" --frames 120 --seed "$seed" --budget-us "$budget" \
      --out-dir "target/tracking_budget/$mesh-$seed" \
      --json "$out/$mesh-seed$seed.json" 2>/dev/null | tee -a "$out/output.txt"
  done
done
