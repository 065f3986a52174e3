"""rsl_rl's Logger with ReFPO's statistics as statistics (refpo_warp/integrations/statistics_logger.py), as the
mjlab integration's runners log: ``Flow/...`` keys are TensorBoard tags and report lines of their own, never
``Loss/Flow/...`` or "Mean Flow/... loss". Marked rsl_rl: CI runs it on rsl-rl-lib 5.0.1 and on the newest 5.x."""

import pytest
from rsl_rl.runners import OnPolicyRunner
from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

from refpo_warp import make_env
from refpo_warp.integrations.statistics_logger import StatisticsLogger, StatisticsRunnerMixin, with_statistics

REPORT = "#" * 80 + "\n Learning iteration 0/2 \n" + f"{'Mean value loss:':>40} 0.1000\n" + "-" * 80 + "\n ETA: 0s\n"


class StatisticsRunner(StatisticsRunnerMixin, OnPolicyRunner):
    pass


def test_statistics_go_above_the_report_footer():
    out = with_statistics(REPORT, {"Flow/ratio_mean": 1.0, "Flow/clip_fraction": 0.25})
    lines = out.splitlines()
    assert lines[-4:] == [
        f"{'Flow/ratio_mean:':>40} 1.0000",
        f"{'Flow/clip_fraction:':>40} 0.2500",
        "-" * 80,
        " ETA: 0s",
    ]
    assert with_statistics("no footer\n", {"Flow/x": 2.0}) == f"no footer\n{'Flow/x:':>40} 2.0000\n"


@pytest.mark.rsl_rl
def test_a_refpo_run_logs_flow_statistics_as_tags_and_report_lines(tmp_path, capsys):
    env = make_env("gridworld", num_envs=8, device="cpu", seed=0)
    cfg = {
        "num_steps_per_env": 16,
        "save_interval": 50,
        "logger": "tensorboard",
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {"class_name": "refpo_warp.models:FlowActor", "hidden_dims": [16, 16], "num_flow_steps": 2},
        "critic": {"class_name": "MLPModel", "hidden_dims": [16, 16]},
        "algorithm": {
            "class_name": "refpo_warp.algorithms:ReFPO",
            "num_mc_samples": 2,
            "num_learning_epochs": 1,
            "rnd_cfg": None,
            "symmetry_cfg": None,
        },
    }
    runner = StatisticsRunner(env, cfg, log_dir=str(tmp_path), device="cpu")
    assert isinstance(runner.logger, StatisticsLogger)
    runner.learn(2)
    printed = capsys.readouterr().out
    assert f"{'Flow/ratio_mean:':>40}" in printed and "Mean reflow loss:" in printed
    assert "Mean Flow/" not in printed
    runner.logger.writer.flush()  # the writer flushes on its own clock: read the events only after both are written
    events = EventAccumulator(str(tmp_path))
    events.Reload()
    tags = set(events.Tags()["scalars"])
    assert {"Flow/ratio_mean", "Flow/clip_fraction", "Flow/explosion_rate", "Loss/reflow", "Loss/surrogate"} <= tags
    assert not [tag for tag in tags if tag.startswith("Loss/Flow")]
    assert [event.step for event in events.Scalars("Flow/ratio_mean")] == [0, 1]
