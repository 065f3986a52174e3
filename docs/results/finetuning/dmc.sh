#!/usr/bin/env bash
# DMC from a weaker demonstrator (docs/results/finetuning/README.md), from the repository root, one process at a time:
#   bash docs/results/finetuning/dmc.sh [dmc_point_mass] [dmc_reacher_easy]
# Per task, under $OUT/<task> (default runs/finetuning/dmc): demonstrator/ (PPO at the task's CPU profile, stopped once
# an evaluation reaches half the from-scratch final return), data/ (200 episodes of the evaluated checkpoint nearest
# that half, half_return_checkpoint.py; its mean
# action plus Gaussian noise 0.3), clone_refpo/ and clone_ppo/ (refpo pretrain), then the sweep finetune_<task> (ReFPO and
# refpo_onestep from the flow clone, PPO from the Gaussian clone, half the CPU profile's env steps, seeds 1-3) into
# runs/sweeps/finetune_<task>. Every step is skipped when its output exists, so the script resumes where it stopped
# (a sweep resumes its own runs). The committed reacher_easy data (dmc/dmc_reacher_easy/) come from a checkpoint other
# than the one half_return_checkpoint.py picks from the committed progress rows (README.md's demonstrator table).
set -euo pipefail
OUT=${OUT:-runs/finetuning/dmc}
TASKS=("${@:-dmc_point_mass dmc_reacher_easy}")
refpo() { nice -n 10 python -m refpo_warp "$@"; }
# Half of PPO's final return from scratch at the CPU profile (docs/results/cpu_dmc/per_task.csv: 869 and 782)
declare -A TARGET=([dmc_point_mass]=435 [dmc_reacher_easy]=391)
for task in ${TASKS[@]}; do
  D="$OUT/$task"
  # the demonstrator trains 8 iterations at a time (a checkpoint and an evaluation every 4) until one reaches the target
  iterations=8
  until CK=$(python docs/results/finetuning/half_return_checkpoint.py "$D/demonstrator" ${TARGET[$task]} 2>/dev/null); do
    if [ -d "$D/demonstrator" ]; then
      iterations=$(( $(ls "$D/demonstrator" | sed -n 's/^model_\([0-9]*\)\.pt$/\1/p' | sort -n | tail -1) + 9 ))
      refpo train run_dir="$D/demonstrator" resume=true max_iterations=$iterations eval.interval=4
    else
      refpo train task=$task algo=ppo seed=1 max_iterations=$iterations runner.save_interval=4 eval.interval=4 \
        run_dir="$D/demonstrator"
    fi
  done
  [ -d "$D/data" ] || refpo collect run_dir="$D/demonstrator" checkpoint="$CK" episodes=200 noise=0.3 initial_noise=zero \
    out="$D/data"
  for algo in refpo ppo; do
    [ -f "$D/clone_$algo/eval.json" ] || refpo pretrain task=$task algo=$algo dataset="$D/data" \
      pretrain.batch_size=2048 run_dir="$D/clone_$algo"
  done
  refpo sweep finetune_${task#dmc_} --jobs 1
done
# The comparison runs of README.md, each resumable the same way (skipped where finished), after the loop above:
#   the normalisers following the rollouts (the behaviour before clone_normalizer=keep), per task:
#     refpo sweep finetune_<task> clone_normalizer=update out=runs/sweeps/finetune_normupdate_<task> --jobs 2
#   the remedies tried against ReFPO's collapse with update, on point_mass:
#     refpo sweep finetune_point_mass 'methods=[refpo,refpo_onestep]' 'actor.action_noise_std=[0.02,0.05]' \
#       clone_normalizer=update out=runs/sweeps/finetune_floor_point_mass --jobs 2
#     refpo sweep docs/results/finetuning/remedies.yaml --jobs 2
#   the remedies with the normalisers held, and the one that held on fresh seeds and on reacher_easy:
#     refpo sweep docs/results/finetuning/remedies.yaml 'methods=[refpo_adaptive,refpo_aspo]' clone_normalizer=keep \
#       out=runs/sweeps/finetune_remedies_keep_point_mass --jobs 2
#     refpo sweep docs/results/finetuning/remedies.yaml 'methods=[refpo_adaptive]' clone_normalizer=keep \
#       'seeds=[4,5,6]' out=runs/sweeps/finetune_remedies_keep_point_mass --jobs 2
#     refpo sweep finetune_point_mass 'methods=[refpo,ppo]' 'seeds=[4,5,6]' --jobs 2
#     refpo sweep docs/results/finetuning/adaptive_reacher.yaml --jobs 2
#   from scratch at the same env steps: refpo sweep finetune_scratch --jobs 2
# then: python docs/results/finetuning/tables.py --dmc (the table, dmc_curves.png, dmc_remedies.png)
