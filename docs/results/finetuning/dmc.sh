#!/usr/bin/env bash
# DMC from a weaker demonstrator (docs/results/finetuning/README.md), from the repository root, one process at a time:
#   bash docs/results/finetuning/dmc.sh [dmc_point_mass] [dmc_reacher_easy]
# Per task, under $OUT/<task> (default runs/finetuning/dmc): demonstrator/ (PPO at the task's CPU profile, a
# checkpoint at every evaluation), data/ (200 episodes of the checkpoint nearest half the final return, its mean action
# plus Gaussian noise 0.3), clone_refpo/ and clone_ppo/ (refpo pretrain), then the sweep finetune_<task> (ReFPO and
# refpo_onestep from the flow clone, PPO from the Gaussian clone, half the CPU profile's env steps, seeds 1-3) into
# runs/sweeps/finetune_<task>. Every step is skipped when its output exists, so the script resumes where it stopped
# (a sweep resumes its own runs).
set -euo pipefail
OUT=${OUT:-runs/finetuning/dmc}
TASKS=("${@:-dmc_point_mass dmc_reacher_easy}")
refpo() { nice -n 10 python -m refpo_warp "$@"; }
for task in ${TASKS[@]}; do
  D="$OUT/$task"
  if [ ! -f "$D/demonstrator/eval.json" ]; then
    refpo train task=$task algo=ppo seed=1 runner.save_interval=4 eval.interval=4 run_dir="$D/demonstrator" \
      $( [ -d "$D/demonstrator" ] && echo resume=true )
  fi
  CK=$(python docs/results/finetuning/half_return_checkpoint.py "$D/demonstrator")
  [ -d "$D/data" ] || refpo collect run_dir="$D/demonstrator" checkpoint="$CK" episodes=200 noise=0.3 sample=mean \
    out="$D/data"
  for algo in refpo ppo; do
    [ -f "$D/clone_$algo/eval.json" ] || refpo pretrain task=$task algo=$algo dataset="$D/data" \
      pretrain.batch_size=2048 run_dir="$D/clone_$algo"
  done
  refpo sweep finetune_${task#dmc_} --jobs 1
done
