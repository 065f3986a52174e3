"""``refpo collect``: a demonstration dataset (Minari format) from a trained run or a scripted demonstrator."""

from __future__ import annotations

from refpo_warp.config.command_options import EXPLAIN, explain_options
from refpo_warp.demonstrations.collect_options import PASSED, CollectOptions, options_usage
from refpo_warp.utils.command_line import Arguments

SUMMARY = "roll out a trained policy (or a scripted demonstrator) and write a Minari demonstration dataset"
USAGE = f"""Collect demonstrations: refpo collect run_dir=<trained run> episodes=K out=PATH [key=value ...]
                                      [env.<opt>=...]
                        refpo collect task=<task> demonstrator=scripted episodes=K out=PATH [demonstrator.<opt>=...]
                                      [env.<opt>=...]

Rolls the policy out on num_envs vectorised envs and writes the K whole episodes (observations, actions, rewards,
terminations, truncations; the spaces, task, env options and policy in metadata.json) as a Minari dataset folder at
out (docs/finetuning.md). Options (refpo_warp/demonstrations/collect_options.py):
{options_usage()}
Env options (env.<option>=VALUE, the task's: refpo train task=<task> --explain): with run_dir=, over the env the
run's evaluation uses (its env options, eval.env's over them; one that changes the policy's inputs or outputs is
refused); over the task's defaults for a scripted demonstrator (built for the same env).
Flags: --explain [KEY,KEY,...] (each option's value and where it comes from; nothing is collected).
GridWorld's scripted demonstrator: demonstrator.up_share=0.7 demonstrator.band=3 (tasks/gridworld/demonstrator.py).

Examples:
    refpo collect task=gridworld demonstrator=scripted episodes=2000 out=data/grid_demo
    refpo collect task=dmc_point_mass_wall demonstrator=scripted env.start_spread=0 episodes=400 out=data/pmw_demo
    refpo collect run_dir=runs/dmc_point_mass/ppo_seed1 episodes=500 noise=0.3 initial_noise=zero out=data/pm_ppo
"""
FLAGS = (EXPLAIN,)
SUBJECTS = 0


def run(args: Arguments) -> None:
    if "--explain" in args.flags:
        print(explain_options("collect", CollectOptions, args.options, args.flag("--explain") or "", PASSED))
        return
    from refpo_warp.config.dotted import parse_overrides
    from refpo_warp.demonstrations.collect import collect
    from refpo_warp.utils.device import set_torch_threads

    set_torch_threads(cuda_cap=4)
    out = collect(parse_overrides(args.options))
    print(
        f"[collect] wrote {out['path']}: {out['episodes']} episodes, {out['steps']:,} steps, return "
        f"{out['return_mean']:.2f}, length {out['length_mean']:.1f} (mean over episodes), {out['wall_s']:.1f} s",
        flush=True,
    )
