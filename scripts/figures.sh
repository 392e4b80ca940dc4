#!/usr/bin/env bash
# Makes every figure and number the README shows, on the current commit:
# the main job (A1 seed 1) and a pile (B1 seed 1) with their curves, PLR out
# of the box, strategy H over many seeds of every family, and the evaluation.
# Writes docs/img/ and docs/figures.md (which names the commit); the README
# points there.
#   scripts/figures.sh            H on seeds 1-20, the whole evaluation (hours)
#   scripts/figures.sh --quick    H on seeds 1-5, the quick evaluation (about an hour)
# Each step's output stays in build/figures/ and is reused when run again
# on the same commit (the benches and the evaluation resume their runs).
set -euo pipefail
cd "$(dirname "$0")/.."

quick=false
[[ "${1:-}" == "--quick" ]] && quick=true
commit=$(git rev-parse --short HEAD)
git diff --quiet HEAD -- . ':!docs' ':!README.md' || {
  echo "figures: the tree differs from commit $commit; commit first, so the figures name what made them" >&2
  exit 1
}
command -v jq >/dev/null || {
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends jq >/dev/null
}
[[ -x build/bin/bench_unload ]] || scripts/setup.sh
ninja -C build plr bench_unload >/dev/null

out=build/figures/$commit
mkdir -p "$out" docs/img
plr=build/bin/plr

run() {  # name config [args...]: a plr run whose report.json exists is not run again
  local name=$1 config=$2
  shift 2
  [[ -f "$out/$name/report.json" ]] && jq -e '.run.finished' "$out/$name/report.json" >/dev/null ||
    "$plr" run "$config" --report "$out/$name" "$@" >"$out/$name.log" 2>&1
}
run unload_a1 configs/unload_sim.yaml
run unload_b1 configs/unload_sim.yaml --set nodes.executor.params.env=B1
run unload_plr configs/unload_plr.yaml
cp "$out/unload_a1/unloading.svg" docs/img/unloading_a1.svg
cp "$out/unload_a1/scene_side.svg" docs/img/scene_side_a1.svg
cp "$out/unload_b1/unloading.svg" docs/img/unloading_b1.svg

if $quick; then seeds=(--quick); eval_args=(--quick); else seeds=(--seeds 20); eval_args=(); fi
build/bin/bench_unload "${seeds[@]}" --out "$out/bench_unload" --json >"$out/bench_unload.json"
"$plr" evaluate configs/evaluate.yaml "${eval_args[@]}" --report "$out/evaluation" \
  >"$out/evaluation.log" 2>&1
for env in A1 B1 A2 B2 C; do
  [[ -f "$out/evaluation/$env.svg" ]] && cp "$out/evaluation/$env.svg" "docs/img/evaluation_$env.svg"
done

run_row() {  # name: boxes, robot time, wasted share of a plr run
  jq -r --arg n "$1" \
    '"| \($n) | \(.boxes_unloaded)/\(.boxes_total) | \(.robot_time_s | floor) s | \((.wasted_share // 0) * 100 | floor) % |"' \
    "$out/$1/report.json"
}
{
  echo "# Figures of commit $commit"
  echo
  echo "Made by \`scripts/figures.sh$($quick && echo ' --quick')\` on $(date -u +%Y-%m-%d)" \
    "($(nproc) cores); the README's figures are these."
  echo
  echo "## Single runs"
  echo
  echo "| run | boxes | robot time | time in actions that moved nothing |"
  echo "|---|---|---|---|"
  run_row unload_a1
  run_row unload_b1
  run_row unload_plr
  echo
  echo "unload_a1: \`configs/unload_sim.yaml\` (H on A1 seed 1); unload_b1: the same on B1 seed 1;"
  echo "unload_plr: \`configs/unload_plr.yaml\` (PLR with the shipped library and chooser on A1 seed 1)."
  echo
  echo "## Strategy H over many seeds (\`bench_unload ${seeds[*]}\`)"
  echo
  echo "| family | runs | emptied | boxes left | median robot time | median boxes/s | median wasted share |"
  echo "|---|---|---|---|---|---|---|"
  jq -r 'to_entries[] | .value as $f |
    "| \(.key) | \($f.runs) | \($f.emptied) | \($f.boxes_left) | \($f.robot_time_s_median | floor) s | \($f.boxes_per_robot_s * 1000 | floor / 1000) | \(($f.wasted_share_median // 0) * 100 | floor) % |"' \
    "$out/bench_unload.json"
  echo
  echo "## Evaluation (\`plr evaluate configs/evaluate.yaml${eval_args[*]:+ ${eval_args[*]}}\`)"
  echo
  echo "Boxes unloaded by 300, 600 and 1,200 robot-seconds and the time to empty a"
  echo "trailer (mean ± standard error; runs capped at \`settings.max_robot_time_s\` ="
  echo "$(jq '.settings.max_robot_time_s' "$out/evaluation/report.json") s)."
  echo
  echo "| env | method | runs | by 300 s | by 600 s | by 1200 s | time to empty |"
  echo "|---|---|---|---|---|---|---|"
  jq -r 'def f: if . == null or .mean == null then "-" else "\(.mean * 10 | round / 10) ± \(.se * 10 | round / 10)" end;
    .environments | to_entries[] | .key as $e | .value.methods | to_entries[] |
    "| \($e) | \(.key) | \(.value.runs) | \(.value.boxes_at["300"] | f) | \(.value.boxes_at["600"] | f) | \(.value.boxes_at["1200"] | f) | \(.value.time_to_empty_s | f) |"' \
    "$out/evaluation/report.json"
  echo
  echo "| claim | holds | margin (SE) |"
  echo "|---|---|---|"
  jq -r '.claims[] | "| \(.claim) | \(.holds) | \(if .z == null then "-" else .z * 100 | round / 100 end) |"' "$out/evaluation/report.json"
  echo
  for env in A1 B1 A2 B2 C; do
    [[ -f "docs/img/evaluation_$env.svg" ]] && echo "![evaluation $env](img/evaluation_$env.svg)"
  done
} >docs/figures.md.tmp
mv docs/figures.md.tmp docs/figures.md
echo "figures: docs/figures.md and docs/img/ made on commit $commit"
