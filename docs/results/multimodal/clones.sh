#!/usr/bin/env bash
# The two-way task's data and clones (docs/results/multimodal/README.md), under runs/multimodal/ (about 20 minutes of
# one core on a 2-core AMD EPYC): 400 demonstrations (60 / 40 left / right), then a clone per actor the fine-tuning
# sweep starts from (configs/sweep/finetune_point_mass_wall.yaml): ReFPO's flow (clone_flow), FPO's (clone_fpo, its
# actor predicts the noise), FPO++'s at the CPU profile (clone_fpo_pp) and PPO's Gaussian (clone_gauss).
set -euo pipefail
out=${1:-runs/multimodal}
[ -e "$out/data/metadata.json" ] || refpo collect task=dmc_point_mass_wall demonstrator=scripted demonstrator.left_share=0.6 episodes=400 out="$out/data"
for pair in refpo:clone_flow fpo:clone_fpo fpo_pp:clone_fpo_pp ppo:clone_gauss; do
  algo=${pair%%:*} name=${pair#*:}
  [ -e "$out/$name/eval.json" ] && continue   # made already
  refpo pretrain task=dmc_point_mass_wall algo="$algo" seed=1 dataset="$out/data" pretrain.batch_size=2048 \
    run_dir="$out/$name"
done
