#!/usr/bin/env bash
# Reruns every stored run the README and docs/ quote, writing each output where the docs read it.
# Needs ../shared/assets/meshes beside the project. Long (about an hour on 2 cores, most of it the
# plugin's runs and the large tracking meshes); run it on a quiet machine, since timings are
# stored. Usage: docs/regenerate.sh [adb|performance|ccd|ccd_reliability|ccd_plugin|tracking|plugin]... (default: all)
#
# Each docs/<topic>.md names the command of each figure; this script is those commands in one place.
set -euo pipefail
cd "$(dirname "$0")/.."
meshes=${STOCHASTIC_COLLISION_MESHES:-../shared/assets/meshes}
topics=("$@")
[ ${#topics[@]} -eq 0 ] && topics=(adb performance ccd tracking plugin)

adb() { # docs/adb.md: the accuracy-against-time report (each mesh against itself, the
  # evaluation seed and a held-out seed), held-out pairs of different meshes, shallow contacts,
  # and the answer model's fit
  local r="cargo run --release --quiet --example accuracy_vs_time --"
  run_adb() { # out-dir args...
    local out=$1
    shift
    mkdir -p "$out"
    $r "$@" --out "$out" 2> >(tr '\r' '\n' | grep 'ADB build [0-9]' | sed 's/^ *//' \
      > "$out/build.txt") | tee "$out/output.txt"
  }
  run_adb docs/adb/report --full --poses 300
  run_adb docs/adb/seed7 --full --poses 300 --seed 7
  run_adb docs/adb/pairs --pairs --poses 300
  run_adb docs/adb/shallow --full --poses 300 --spread 0.02
  # The published rule checked: on trees built as the papers build them (smooth meshes and
  # CAD-like parts) and on the CAD-like parts with this crate's trees.
  run_adb docs/adb/paper/smooth --full --paper-trees --poses 300
  run_adb docs/adb/paper/cad --cad --paper-trees --poses 300
  run_adb docs/adb/paper/cad_default_trees --cad --poses 300
  # The answer model (adb::AnswerModel::FITTED): its fit on the training pairs and seeds, and
  # its held-out check.
  mkdir -p docs/adb/answer_model
  { echo "\$ cargo run --release --example fit_answer_model -- --poses 80"
    cargo run --release --quiet --example fit_answer_model -- --poses 80 2>/dev/null; } |
    tee docs/adb/answer_model/output.txt
}

performance() { # docs/performance.md: the exact query against parry3d
  mkdir -p docs/performance
  { echo "\$ cargo bench --bench exact_vs_parry -- nomatch"
    cargo bench --quiet --bench exact_vs_parry -- nomatch 2>/dev/null; } |
    tee docs/performance/exact_vs_parry.txt
}

ccd() { # docs/ccd.md: continuous collision against the discrete query and parry3d
  { echo "\$ cargo bench --bench ccd"; cargo bench --quiet --bench ccd 2>/dev/null; } |
    tee docs/ccd/bench.txt
  ccd_reliability
  ccd_plugin
}

ccd_reliability() { # docs/ccd.md: the continuous ADB query's confidence on swept pairs
  # The swept answer model's fit on its training meshes and seeds (its weights are in
  # src/ccd/swept_answer_model.rs), then its evaluation on other meshes and seeds.
  { echo "\$ cargo run --release --example fit_swept_answer_model"
    cargo run --release --quiet --example fit_swept_answer_model 2>/dev/null; } |
    tee docs/ccd/swept_answer_model.txt
  {
    for args in "--svg docs/ccd/continuous_adb_reliability.svg" "--seed 2" "--seed 3"; do
      echo "\$ cargo run --release --example continuous_adb_reliability -- $args"
      # shellcheck disable=SC2086
      cargo run --release --quiet --example continuous_adb_reliability -- $args 2>/dev/null
    done
  } | tee docs/ccd/continuous_adb_reliability.txt
}

ccd_plugin() { # docs/ccd.md: continuous collision in the plugin (tunnel, cannonball at 10x, needle)
  {
    for args in "--speed 10 --svg docs/ccd/tunnel.svg" "--speed 10 --seed 2" "--speed 10 --seed 3" \
      "--speed 3" "--speed 30"; do
      echo "\$ cargo run --release --example tunnel -- $args"
      # shellcheck disable=SC2086
      cargo run --release --quiet --example tunnel -- $args
    done
    echo "\$ cargo run --release --example cannonball -- 300 0.5 1000 0.2 off 10"
    cargo run --release --quiet --example cannonball -- 300 0.5 1000 0.2 off 10
    for args in "--svg docs/ccd/needle.svg" "--seed 2" "--seed 3"; do
      echo "\$ cargo run --release --example needle -- $args"
      # shellcheck disable=SC2086
      cargo run --release --quiet --example needle -- $args
    done
  } | tee docs/ccd/plugin.txt
}

tracking() { # docs/tracking.md: tracking against the exact self-collision pass
  # The exact self pass against parry3d's (quoted in its own section).
  { echo "\$ cargo bench --bench self_pass_vs_parry"
    cargo bench --quiet --bench self_pass_vs_parry 2>/dev/null; } |
    tee docs/tracking/self_pass/output.txt
  local q="cargo run --release --quiet --example tracking_quality --"
  # Training meshes (the tracker's constants were chosen on these, seed 1).
  $q --frames 480 --sweep 16,32,64,128,256 --out-dir docs/tracking/generated_tube \
    --json docs/tracking/generated_tube/result.json
  $q --mesh "$meshes/plane_50x50.obj" --frames 480 --sweep 16,32,64,128,256 --pairs-per-frame 64 \
    --out-dir docs/tracking/plane_50x50 --json docs/tracking/plane_50x50/result.json
  # The main runs use the defaults (at least 64 new pairs per frame, more where the overlapping
  # patch pairs are many: TrackerConfig::overlaps_per_pair); the sweeps fixed numbers.
  $q --mesh "$meshes/large-intestine-sf+-hf-.obj" --frames 120 --sweep 16,32,64,128,256 \
    --out-dir "docs/tracking/large-intestine-sf+-hf-" \
    --json "docs/tracking/large-intestine-sf+-hf-/result.json"
  $q --mesh "$meshes/small_intestine_100k.obj" --frames 120 --sweep 64,128,256,384,512,768 \
    --out-dir docs/tracking/small_intestine_100k \
    --json docs/tracking/small_intestine_100k/result.json
  # Held out: meshes it was not tuned on, other seeds, the defaults.
  : > docs/tracking/held_out/output.txt
  for mesh in bunny teapot suzanne spot large_intestine_20k armadillo dragon_50k stanford-bunny; do
    for seed in 3 4 5; do
      echo "== $mesh seed $seed" | tee -a docs/tracking/held_out/output.txt
      $q --mesh "$meshes/$mesh.obj" --frames 120 --seed "$seed" --no-sweep \
        --out-dir "target/tracking_held_out/$mesh-$seed" \
        --json "docs/tracking/held_out/$mesh-seed$seed.json" | tee -a docs/tracking/held_out/output.txt
    done
  done
  # Held out, generated: a new random-centre-line tube and a new noisy sphere per seed
  # (whirled), and the cloth crumpled (folded like paper) with each seed.
  for spec in "random-tube whirl" "noisy-sphere whirl" "cloth crumple"; do
    set -- $spec
    for seed in 3 4 5; do
      echo "== generated:$1 ($2) seed $seed" | tee -a docs/tracking/held_out/output.txt
      $q --mesh "generated:$1" --motion "$2" --frames 120 --seed "$seed" --no-sweep \
        --out-dir "target/tracking_held_out/$1-$seed" \
        --json "docs/tracking/held_out/generated-$1-seed$seed.json" | tee -a docs/tracking/held_out/output.txt
    done
  done
  # Growth with the mesh at the same budget: the 5k cloth and the 100k intestine, 2 ms a step.
  mkdir -p docs/tracking/growth
  : > docs/tracking/growth/output.txt
  for mesh in plane_50x50 small_intestine_100k; do
    echo "== $mesh, budget 2000 us" | tee -a docs/tracking/growth/output.txt
    $q --mesh "$meshes/$mesh.obj" --frames 120 --budget-us 2000 \
      --out-dir "target/tracking_growth/$mesh" \
      --json "docs/tracking/growth/$mesh.json" | tee -a docs/tracking/growth/output.txt
  done
  docs/tracking/budget.sh
}

plugin() { # docs/plugin.md: the plugin's stage timings and the pile's response runs
  docs/plugin/measure.sh
  docs/plugin/pile_response.sh
}

for topic in "${topics[@]}"; do
  echo "=== $topic"
  "$topic"
done
