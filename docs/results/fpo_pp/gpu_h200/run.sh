#!/usr/bin/env bash
# Issue 39 on the GPU: 20 training iterations of FPO++ and of ReFPO on dmc_cartpole_balance at the CUDA profile.
# parts 1 and 2 were copied to /tmp/kit by the two calls before (a call keeps only the ignored paths it carries)
cp .gpukit/3/part-* /tmp/kit/ && rm -rf /tmp/site && mkdir -p /tmp/site
cat /tmp/kit/part-* | xz -d | tar -x -C /tmp/site && touch /tmp/site/.kit-ok
source .gpukit/3/unpack.sh
python3 -c "import warp, newton, rsl_rl; print('kit ok', warp.__version__)" || exit 3
# the checkout on this machine is not installed: the package's configs and tasks are its top-level folders
[[ -e refpo_warp/configs ]] || ln -s ../configs refpo_warp/configs
[[ -e refpo_warp/tasks ]] || ln -s ../tasks refpo_warp/tasks
nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv | tee "$OUT/gpu.txt"
for spec in "fpo_pp 230" "refpo 170"; do
  set -- $spec
  start=$(date +%s.%N)
  timeout "$2" python3 tools/train.py task=dmc_cartpole_balance algo=$1 device=cuda:0 max_iterations=20 seed=1 \
    eval.interval=0 eval.at_end=false run_dir=/tmp/runs/$1 > "$OUT/$1.log" 2>&1
  rc=$?
  end=$(date +%s.%N)
  echo "$1 rc=$rc wall_s=$(python3 -c "print(round($end - $start, 1))")" | tee -a "$OUT/summary.txt"
  cp /tmp/runs/$1/progress.jsonl "$OUT/$1_progress.jsonl" 2>/dev/null
  cp /tmp/runs/$1/config.yaml "$OUT/$1_config.yaml" 2>/dev/null
  tail -3 "$OUT/$1.log"
done
