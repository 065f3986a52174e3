"""``refpo pretrain``: behaviour cloning of an algorithm's actor from a demonstration dataset."""

from __future__ import annotations

from refpo_warp.config.command_options import EXPLAIN
from refpo_warp.utils.command_line import Arguments

SUMMARY = "clone an algorithm's actor from a demonstration dataset (flow: CFM loss, Gaussian: max. likelihood)"
USAGE = """Behaviour cloning: refpo pretrain task=<task> algo=<algo> dataset=PATH [key=value ...]

Clones the actor algo trains (a flow by its CFM loss, a Gaussian by maximum likelihood) from a Minari dataset
(refpo collect writes one), with the observation normaliser from the data, a held-out validation loss and early
stopping; evaluates the clone and writes model_0.pt (rsl_rl's checkpoint layout), config.yaml, progress.jsonl (one
row per epoch), TensorBoard events and eval.json into run_dir (default runs/<task>/pretrain_<algo>_seed<seed>).
Fine-tune it with: refpo train task=<task> algo=<algo> init_from=<that run dir>  (docs/finetuning.md)

Options: pretrain.<key>=VALUE (epochs, batch_size, learning_rate, validation_fraction, patience, num_pairs,
dataset_actions, squash_margin: PretrainOptions in refpo_warp/config/run_options.py; `--explain pretrain` lists each
with its default and meaning); any run option (seed, device, eval.flow_steps, the actor's sizes, ...) as for refpo
train.
Flags: --explain [KEY,KEY,...] (the value of each option and the layer that set it, as refpo train's; nothing is run).

Examples:
    refpo pretrain task=gridworld algo=refpo dataset=data/grid_demo
    refpo pretrain task=gridworld algo=ppo dataset=data/grid_demo run_dir=runs/grid_bc_gauss
"""
FLAGS = (EXPLAIN,)
SUBJECTS = 0


def run(args: Arguments) -> None:
    if "--explain" in args.flags:
        from refpo_warp.config.explain import explain
        from refpo_warp.demonstrations.pretrain_run import pretrain_config

        keys = [k.strip() for k in (args.flag("--explain") or "").split(",") if k.strip()]
        print(explain(pretrain_config(args.options), keys or None), flush=True)
        return
    from refpo_warp.demonstrations.pretrain_run import pretrain
    from refpo_warp.utils.console import headline_numbers, summary_block
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    out = pretrain(args.options)
    run_dir = out["checkpoint"].rsplit("/", 1)[0] if "/" in out["checkpoint"] else "."
    outputs = [("run dir", run_dir), ("checkpoint", out["checkpoint"]), ("eval.json", f"{run_dir}/eval.json")]
    data = out["dataset"]
    described = f"{data['episodes']} episodes, return {data['return_mean']:.2f}, length {data['length_mean']:.1f}"
    numbers = [("dataset", described), *headline_numbers(out)]
    title = f"Cloned {out['task']} / {out['algo']} (best epoch {out['pretrain']['best_epoch']})"
    print(summary_block(title, outputs, numbers), flush=True)
