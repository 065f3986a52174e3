#!/usr/bin/env bash
# The job this project runs when it has a GPU for a few minutes: each step with its own time limit, all of them within
# BUDGET_S seconds (one 10-minute call of a lent machine), in this order:
#   1. FPO++'s small-task recipe and ReFPO on dmc_point_mass at the CUDA profile, 10M env steps, seed 1;
#   2. the two-way task: 10,000 scripted demonstrations at the CUDA profile, the flow clone, ReFPO fine-tuned (seed 1);
#   3. refpo bench train at the paper's DMC size (dmc_cartpole_balance, PPO and ReFPO): env steps/s and the split.
# Every step's wall time goes to $OUT/steps.tsv, each run's small files to $OUT/<name>/.
# With no warm Warp kernel cache, compile the CUDA kernels ahead of time for the env counts it uses (some MuJoCo Warp
# kernels bake in the number of worlds): dmc_point_mass, dmc_point_mass_wall and dmc_cartpole_balance at 2048, 128
# and 64 envs. Status: checked at toy sizes on the CPU; not yet run on a GPU.
# On the CPU, for a dry run of the same steps at toy sizes: DEVICE=cpu TOY=1 OUT=/tmp/out bash docs/results/gpu/lent_gpu.sh
set -uo pipefail
OUT=${OUT:?set OUT}
DEVICE=${DEVICE:-cuda:0}
BUDGET_S=${BUDGET_S:-540}
if [[ $DEVICE != cpu ]]; then
  # a machine without the dependencies installed gets them from the unpacked kit parts carried before (.gpukit/)
  for u in .gpukit/*/unpack.sh; do :; done
  if [[ -f ${u:-} ]]; then
    source "$u" || { echo "kit unpack failed"; exit 3; }
    # a checkout that is not installed: the package's configs and tasks are its top-level folders
    [[ -e refpo_warp/configs ]] || ln -s ../configs refpo_warp/configs
    [[ -e refpo_warp/tasks ]] || ln -s ../tasks refpo_warp/tasks
  fi
  nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$OUT/gpu.txt"
fi
runs=${RUNS:-/tmp/gpu_runs}; mkdir -p "$runs"
if [[ -n ${TOY:-} ]]; then  # toy sizes for the CPU dry run
  size=(num_envs=8 runner.num_steps_per_env=16 eval.num_envs=4 eval.interval_num_envs=4)
  pm_steps=256 bench=(iterations=1 warmup=0) episodes=16 ft_steps=256 pre=(pretrain.epochs=1)
else
  size=()
  pm_steps=10000000 bench=(iterations=2 warmup=1) episodes=10000 ft_steps=4915200
  pre=(pretrain.epochs=5 pretrain.batch_size=8192)
fi
end=$((SECONDS + BUDGET_S))
printf 'step\trc\twall_s\n' > "$OUT/steps.tsv"
step() {  # step NAME LIMIT_S command...: the command's output to $OUT/NAME.log, its wall time to steps.tsv
  local name=$1 t=$2; shift 2; local left=$((end - SECONDS))
  ((left < 15)) && { printf '%s\tskipped\t0\n' "$name" >> "$OUT/steps.tsv"; return; }
  ((t > left)) && t=$left
  local s0; s0=$(date +%s.%N)
  timeout -s KILL "$t" "$@" > "$OUT/$name.log" 2>&1; local rc=$?
  printf '%s\t%s\t%s\n' "$name" "$rc" "$(python3 -c "print(round($(date +%s.%N) - $s0, 1))")" >> "$OUT/steps.tsv"
  tail -2 "$OUT/$name.log"
}
keep() {  # a run's small files (no checkpoints) into $OUT/NAME
  mkdir -p "$OUT/$1"; (cd "$runs/$1" 2>/dev/null && find . -maxdepth 1 -type f ! -name '*.pt' -exec cp {} "$OUT/$1/" \;)
}
refpo() { python3 -m refpo_warp "$@"; }

# FPO++'s recipe stores 256 (tau, eps) pairs per action: at the CUDA profile's 983,040 transitions its 4 minibatches
# (245,760 transitions x 256 pairs each) need about 120 GB of activations; 32 minibatches of 30,720 (its own
# cartpole's are 16,384) fit the card.
step pm_fpo_pp_small 230 refpo train task=dmc_point_mass algo=fpo_pp_small device="$DEVICE" seed=1 \
  total_env_steps=$pm_steps algorithm.num_mini_batches=32 eval.interval=5 "${size[@]}" run_dir="$runs/pm_fpo_pp_small"
keep pm_fpo_pp_small
step pm_refpo 110 refpo train task=dmc_point_mass algo=refpo device="$DEVICE" seed=1 total_env_steps=$pm_steps \
  eval.interval=5 "${size[@]}" run_dir="$runs/pm_refpo"
keep pm_refpo
step wall_collect 60 refpo collect task=dmc_point_mass_wall demonstrator=scripted demonstrator.left_share=0.6 \
  episodes=$episodes num_envs=$((episodes < 2048 ? episodes : 2048)) device="$DEVICE" out="$runs/wall_data"
cp "$runs/wall_data/metadata.json" "$OUT/wall_data_metadata.json" 2>/dev/null
step wall_clone 90 refpo pretrain task=dmc_point_mass_wall algo=refpo seed=1 dataset="$runs/wall_data" \
  device="$DEVICE" "${pre[@]}" "${size[@]}" run_dir="$runs/wall_clone"
keep wall_clone
step wall_finetune 90 refpo train task=dmc_point_mass_wall algo=refpo device="$DEVICE" seed=1 \
  init_from="$runs/wall_clone" total_env_steps=$ft_steps eval.interval=1 "${size[@]}" run_dir="$runs/wall_finetune"
keep wall_finetune
step bench_cartpole_balance 100 refpo bench train task=dmc_cartpole_balance 'algo=[ppo,refpo]' device="$DEVICE" \
  "${bench[@]}" "${size[@]}" out="$OUT/bench_train_dmc_cartpole_balance.json"
cat "$OUT/steps.tsv"
