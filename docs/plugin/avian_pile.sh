#!/usr/bin/env bash
# The pile side by side with avian3d 0.8 (integrations/avian's `pile_vs_avian` example): the same
# triangles as trimesh colliders, box, seeded spawn and initial velocities, rotations locked,
# 60 Hz, 2 threads, headless; per-step collision time over the falling phase (the first 120
# steps) at 1,000 and 4,000 bodies, this crate without a budget, the two apps' steps
# interleaved. Seeds 2 and 3 (the pipeline was tuned on seed 1) with the pile's bodies
# (Suzanne, 968 triangles, every fourth body when the shared mesh is present); seed 2 again
# without Suzanne (small meshes only), and with sleeping off on both sides.
# Output: docs/plugin/runs/avian_pile.txt. Takes about 12 minutes on 2 cores (avian's solver is
# most of it).
# Usage: docs/plugin/avian_pile.sh [output file]
set -euo pipefail
cd "$(dirname "$0")/../.."
root=$(pwd)
out=${1:-$root/docs/plugin/runs/avian_pile.txt}
mkdir -p "$(dirname "$out")"
# Which main crate was measured (the example builds it by path from this checkout).
if commit=$(git rev-parse --short HEAD 2>/dev/null); then
  if [ -n "$(git status --porcelain -- src Cargo.toml Cargo.lock)" ]; then
    commit="$commit + uncommitted changes to the main crate"
  fi
else
  commit=${MAIN_CRATE_COMMIT:-unknown}
fi
cd integrations/avian
cargo build --release --ignore-rust-version --example pile_vs_avian
bin=${CARGO_TARGET_DIR:-target}/release/examples/pile_vs_avian
{
  echo "# docs/plugin/avian_pile.sh: main crate $commit; $(rustc --version); $(nproc) cores"
  for args in "--seed 2" "--seed 3" "--seed 2 --no-suzanne" "--seed 2 --no-sleep"; do
    echo
    # shellcheck disable=SC2086
    "$bin" --bodies 1000,4000 --steps 120 $args
  done
} | tee "$out"
