#!/usr/bin/env bash
# The GridWorld modes table of docs/results/finetuning/README.md, from the repository root (one process at a time):
#   bash docs/results/finetuning/gridworld.sh && python docs/results/finetuning/tables.py
# Outputs under $OUT (default runs/finetuning/gridworld): data/ (the Minari dataset), clone_flow/, clone_gauss/
# (refpo pretrain runs), refpo_from_flow/, fpo_from_flow/, ppo_from_gauss/ (fine-tuning runs).
set -euo pipefail
OUT=${OUT:-runs/finetuning/gridworld}
STEPS=${STEPS:-131072}   # 64 iterations of 2,048 env steps: half the paper's from-scratch budget (260k)
refpo() { nice -n 10 python -m refpo_warp "$@"; }
[ -d "$OUT/data" ] || refpo collect task=gridworld demonstrator=scripted episodes=2000 seed=1 out="$OUT/data"
[ -f "$OUT/clone_flow/eval.json" ] || refpo pretrain task=gridworld algo=refpo dataset="$OUT/data" run_dir="$OUT/clone_flow"
[ -f "$OUT/clone_gauss/eval.json" ] || refpo pretrain task=gridworld algo=ppo dataset="$OUT/data" run_dir="$OUT/clone_gauss"
for algo in refpo fpo; do
  [ -f "$OUT/${algo}_from_flow/eval.json" ] || refpo train task=gridworld algo=$algo init_from="$OUT/clone_flow" \
    total_env_steps=$STEPS run_dir="$OUT/${algo}_from_flow"
done
[ -f "$OUT/ppo_from_gauss/eval.json" ] || refpo train task=gridworld algo=ppo init_from="$OUT/clone_gauss" \
  total_env_steps=$STEPS run_dir="$OUT/ppo_from_gauss"
